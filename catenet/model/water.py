"""Water as a medium: its density, still surface, current profile and waves (the
kinematics a node sees), and each edge's hydrodynamic coefficients.

Kinematics (``Water.flow``): the current is piecewise linear in z between the given
points and constant beyond them; each regular wave is linear (Airy) theory,

    eta = a cos(theta),  theta = k (x cos beta + y sin beta) - omega t + phase,
    u_h = a omega C(z) cos(theta) (cos beta, sin beta),  w = a omega S(z) sin(theta),
    C = cosh(k (z' + h)) / sinh(k h),  S = sinh(k (z' + h)) / sinh(k h),

with omega^2 = g k tanh(k h) (finite depth h; deep water: C = S = exp(k z')) and z' the
depth below the still water level (z' <= 0). No stretching: the kinematics are those of
linear theory below the still water level, and a point above it sees the kinematics at
that level (a point above it is dry: buoyancy, drag and added mass count the wetted part
by the still level). A JONSWAP sea is a sum of such components with seeded random
phases. ``ramp`` grows the waves smoothly from nothing over its length (the current is
there from the start).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

G_STANDARD = 9.80665  # m/s^2, where a case has no gravity to take it from
CHUNK = 200_000  # wave components x points evaluated at once (memory: a few such arrays)


@dataclass(frozen=True)
class Wave:
    """One regular (Airy) wave component: amplitude [m], angular frequency [rad/s],
    direction [rad from +x toward +y], phase [rad]."""

    amplitude: float
    omega: float
    direction: float = 0.0
    phase: float = 0.0


def wave_number(omega: float, g: float, depth: float | None) -> float:
    """k of omega^2 = g k tanh(k h) (deep water, h None: omega^2 / g), by Newton from
    the deep-water value (the function is increasing and concave in k)."""
    k = omega * omega / g
    if depth is None:
        return k
    k = max(k, omega / math.sqrt(g * depth))  # shallow-water start: above the root
    for _ in range(100):
        th = math.tanh(k * depth)
        f = g * k * th - omega * omega
        df = g * th + g * k * depth * (1.0 - th * th)
        step = f / df
        k -= step
        if abs(step) <= 1e-15 * k:
            break
    return k


def jonswap(
    hs: float, tp: float, gamma: float, seed: int, count: int = 100, direction: float = 0.0
) -> tuple[Wave, ...]:
    """Regular components of a JONSWAP sea of significant height hs and peak period tp
    (Goda's normalisation of the spectrum, so that 4 sqrt(m0) = hs): ``count`` equal
    bands of omega over [0.5, 3] omega_p, each an amplitude sqrt(2 S dw) at the band's
    centre and a phase from the seeded generator (numpy's default_rng(seed))."""
    wp = 2.0 * math.pi / tp
    edges = np.linspace(0.5 * wp, 3.0 * wp, count + 1)
    w = 0.5 * (edges[1:] + edges[:-1])
    dw = edges[1] - edges[0]
    sigma = np.where(w <= wp, 0.07, 0.09)
    peak = gamma ** np.exp(-((w - wp) ** 2) / (2.0 * sigma**2 * wp**2))
    shape = w ** (-5.0) * np.exp(-1.25 * (wp / w) ** 4) * peak
    m0 = float(np.sum(shape) * dw)
    s = shape * (hs / 4.0) ** 2 / m0  # 4 sqrt(m0) = hs exactly for the bands kept
    phases = np.random.default_rng(seed).uniform(0.0, 2.0 * math.pi, count)
    amps = np.sqrt(2.0 * s * dw)
    return tuple(
        Wave(float(a), float(o), direction, float(p))
        for a, o, p in zip(amps, w, phases, strict=True)
    )


@dataclass(frozen=True, eq=False)
class Water:
    """Still water below ``surface`` (z) of ``density`` [kg/m^3]; ``g`` [m/s^2] the
    gravity that makes buoyancy and waves; ``current`` (K, 3) rows (z, ux, uy) sorted by
    z (None: none); ``waves`` regular components; ``depth`` [m] from the surface to the
    seabed (None: deep water); ``ramp`` [s]: the waves' smooth start."""

    density: float
    surface: float = 0.0
    g: float = G_STANDARD
    current: np.ndarray | None = None
    waves: tuple[Wave, ...] = ()
    depth: float | None = None
    ramp: float = 0.0
    _k: tuple[float, ...] = field(default=(), repr=False)
    # the components as arrays (W,): k, omega, amplitude x omega, cos and sin of the
    # direction, phase
    _table: tuple[np.ndarray, ...] = field(default=(), repr=False)

    def __post_init__(self) -> None:
        ks = tuple(wave_number(w.omega, self.g, self.depth) for w in self.waves)
        object.__setattr__(self, "_k", ks)
        omega = np.array([w.omega for w in self.waves], dtype=np.float64)
        direction = np.array([w.direction for w in self.waves], dtype=np.float64)
        table = (
            np.array(ks, dtype=np.float64),
            omega,
            np.array([w.amplitude for w in self.waves], dtype=np.float64) * omega,
            np.cos(direction),
            np.sin(direction),
            np.array([w.phase for w in self.waves], dtype=np.float64),
        )
        object.__setattr__(self, "_table", table)

    @property
    def moves(self) -> bool:
        """Whether the water moves (a current or waves)."""
        return self.current is not None or bool(self.waves)

    def _current(self, z: np.ndarray) -> np.ndarray:
        out = np.zeros((z.shape[0], 3))
        if self.current is not None:
            table = self.current
            out[:, 0] = np.interp(z, table[:, 0], table[:, 1])
            out[:, 1] = np.interp(z, table[:, 0], table[:, 2])
        return out

    def envelope(self, t: float) -> tuple[float, float]:
        """The waves' ramp factor at time t and its time derivative (1, 0 past the ramp):
        (1 - cos(pi t / ramp)) / 2 over the ramp, so the waves start at rest."""
        if self.ramp <= 0.0 or t >= self.ramp:
            return 1.0, 0.0
        if t <= 0.0:
            return 0.0, 0.0
        q = math.pi / self.ramp
        return 0.5 * (1.0 - math.cos(q * t)), 0.5 * q * math.sin(q * t)

    def flow(
        self, x: np.ndarray, t: float | None, waves: bool = True
    ) -> tuple[np.ndarray, np.ndarray]:
        """The water's velocity and acceleration (N, 3) at the points x (N, 3) at time t
        (None, or ``waves`` False: the current alone, acceleration zero)."""
        x = np.asarray(x, dtype=np.float64)
        vel = self._current(x[:, 2])
        acc = np.zeros_like(vel)
        if t is None or not waves or not self.waves:
            return vel, acc
        r, dr = self.envelope(t)
        if r == 0.0 and dr == 0.0:
            return vel, acc
        zp = np.minimum(x[:, 2] - self.surface, 0.0)
        if self.depth is not None:
            zp = np.maximum(zp, -self.depth)
        k, omega, aw, cb, sb, phase = self._table
        chunk = max(1, CHUNK // len(k))  # (components x points at a time)
        for a in range(0, len(x), chunk):
            at = slice(a, a + chunk)
            theta = (
                np.outer(k * cb, x[at, 0])
                + np.outer(k * sb, x[at, 1])
                + (phase - omega * t)[:, None]
            )
            c, s = _profiles(k[:, None], zp[None, at], self.depth)
            cos, sin = np.cos(theta), np.sin(theta)
            uh, w = aw[:, None] * c * cos, aw[:, None] * s * sin  # (W, n) each
            duh = (aw * omega)[:, None] * c * sin  # d/dt at fixed r
            dw = -(aw * omega)[:, None] * s * cos
            horizontal = r * duh + dr * uh
            vel[at, 0] += r * (cb @ uh)
            vel[at, 1] += r * (sb @ uh)
            vel[at, 2] += r * w.sum(axis=0)
            acc[at, 0] += cb @ horizontal
            acc[at, 1] += sb @ horizontal
            acc[at, 2] += (r * dw + dr * w).sum(axis=0)
        return vel, acc


def _profiles(k: np.ndarray, zp: np.ndarray, depth: float | None) -> tuple[np.ndarray, np.ndarray]:
    """cosh(k (z' + h)) / sinh(k h) and sinh(k (z' + h)) / sinh(k h) at depths z' <= 0
    (k and zp broadcast: components x points), written with decaying exponentials only
    (no overflow at any k h); deep: exp(k z')."""
    top = np.exp(k * zp)
    if depth is None:
        return top, top
    bottom = np.exp(-k * (zp + 2.0 * depth))
    scale = -1.0 / np.expm1(-2.0 * k * depth)  # (to round-off where k h is small)
    return (top + bottom) * scale, (top - bottom) * scale


@dataclass(frozen=True, eq=False)
class Hydro:
    """Each edge's hydrodynamic data (E,): drag coefficients normal ``cd_n`` and
    tangential ``cd_t`` (on the projected area d l and on the surface pi d l), added-mass
    coefficients ``ca_n``, ``ca_t``, the hydrodynamic diameter ``diameter`` [m] and the
    displaced volume per unstressed length ``area`` [m^2]."""

    cd_n: np.ndarray
    cd_t: np.ndarray
    ca_n: np.ndarray
    ca_t: np.ndarray
    diameter: np.ndarray
    area: np.ndarray

    @staticmethod
    def uniform(n_edges: int, **values: float) -> Hydro:
        """Every edge the same (keys as the fields)."""
        return Hydro(**{k: np.full(n_edges, float(v)) for k, v in values.items()})


def added_mass_blocks(
    n: int, nodes: np.ndarray, tang: np.ndarray, normal: np.ndarray, axial: np.ndarray
) -> np.ndarray:
    """(n, 3, 3) added-mass blocks [kg]: at each entry's node, normal (I - t t^T) +
    axial t t^T for its unit tangent t (a zero tangent, a zero-length edge: no
    direction, 2/3 normal I). ``nodes`` (K,), ``tang`` (K, 3), ``normal``, ``axial`` (K,)."""
    blocks = np.zeros((n, 3, 3))
    if not len(nodes):
        return blocks
    tt = np.einsum("ki,kj->kij", tang, tang)
    lateral = np.eye(3)[None] - tt
    lateral[np.all(tang == 0.0, axis=1)] = np.eye(3) * (2.0 / 3.0)
    own = np.asarray(normal)[:, None, None] * lateral + np.asarray(axial)[:, None, None] * tt
    np.add.at(blocks, nodes, own)
    return blocks
