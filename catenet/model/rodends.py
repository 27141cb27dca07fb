"""Rod ends on a coupled 6 x 6 elastic support (``[[supports.spring]]`` with a 6x6
``stiffness``): a foundation that holds a rod's end node and its direction at once,
translation and rotation coupled, in any orientation.

The support's stiffness K (6 x 6, world axes, symmetric positive semidefinite) acts on
q = (u, theta): u = x - X the end node's displacement [m] and theta its rotation [rad],
K = [[K_uu, K_ut], [K_tu, K_tt]] with K_uu [N/m], K_ut [N/rad] and K_tt [N m/rad]: the
support's force on the rod is -(K q)_u, its moment -(K q)_t.

The rod's end is a node c and its end edge (c, o) of given direction t0. The rotation of
the foot, theta_f, is not a DOF: the end edge's direction t turns from t0 by the foot's
turn plus the rod's own bending over the half edge next to the foot, whose rotational
stiffness is 2 EI / l (the clamp of ``catenet.model.rods``: EI / l |t - t0|^2). The foot
is eliminated exactly (a Schur complement, once) from

    U = 1/2 q_f^T K q_f + 1/2 (2 EI / l) |w - P theta_f|^2,   q_f = (u, theta_f),

w the end edge's turn (``catenet.terms.rodends``: (t0 x t) / cos(theta / 2), of length
|t - t0| = 2 sin(theta / 2)), P = 1 - t0 t0^T: U = 1/2 (u, w)^T S (u, w). A rigid K gives
the clamp (the end edge's own bending only), a zero one a free end, and so the foot
turns (K^-1 wrench)_t to O(l^2) under a small load. The foot's twist is the free
direction of theta_f here, which eliminates K's twist row and column by the same Schur
complement. A rod that twists (GJ > 0) has its twist held by the spring's twist
stiffness k_t = t0^T K_tt t0 in series with it (``twist_ends``: the twist term adds 1 /
k_t to the segment's compliance) where K's row about the axis holds nothing else; a
6x6 that couples it with the other rows is refused at a twisting rod's end
(``twist_coupled``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from catenet.errors import ConfigError

#: Eigenvalues of a 6x6 below -SYMMETRY x its largest entry are not round-off.
SYMMETRY = 1e-12


def spring6_matrix(stiffness, what: str = "stiffness") -> np.ndarray | None:
    """The 6 x 6 of ``stiffness`` if it is one (None: not an array of six), a 6x6 or
    [kx, ky, kz, krx, kry, krz] (uncoupled, along x, y, z), checked:
    finite, symmetric, positive semidefinite and not zero; a ConfigError naming
    ``what`` otherwise."""
    from catenet.model.limits import MAGNITUDE, too_large

    rows = stiffness if isinstance(stiffness, (list, tuple)) else None
    if rows is None or len(rows) != 6:
        return None
    shown = np.asarray(stiffness, dtype=object).tolist()
    accepted = (
        "a 6x6 [[k_uu, k_ut], [k_tu, k_tt]] (rows for x, y, z, rx, ry, rz: N/m, N/rad and "
        f"N m/rad) must be symmetric, positive semidefinite, finite (within {too_large()}) "
        "and not zero"
    )
    try:
        k = np.asarray(stiffness, dtype=np.float64)
    except (TypeError, ValueError):
        raise ConfigError(f"{what} = {shown!r}: six rows of six numbers: {accepted}") from None
    if k.shape == (6,):  # [kx, ky, kz, krx, kry, krz]: uncoupled, along the world axes
        if not np.all(np.isfinite(k) & (k >= 0.0)):
            raise ConfigError(
                f"{what} = {shown!r}: [kx, ky, kz, krx, kry, krz] must each be finite and >= 0"
            )
        k = np.diag(k)
    if k.shape != (6, 6):
        raise ConfigError(f"{what}: shape {k.shape}, not (6, 6): {accepted}")
    if not np.all(np.isfinite(k)) or np.abs(k).max() > MAGNITUDE:
        raise ConfigError(f"{what} = {shown!r}: {accepted}")
    scale = float(np.abs(k).max())
    if scale == 0.0:
        raise ConfigError(f"{what}: all zero: {accepted}")
    asym = np.abs(k - k.T)
    if asym.max() > SYMMETRY * scale:
        i, j = np.unravel_index(int(np.argmax(asym)), k.shape)
        raise ConfigError(
            f"{what}: not symmetric: row {i} column {j} is {float(k[i, j]):g}, row {j} column {i} "
            f"{float(k[j, i]):g}: {accepted}"
        )
    k = 0.5 * (k + k.T)
    # the diagonal's scale per row: units differ between the translation and the turn
    d = np.sqrt(np.maximum(np.diag(k), 0.0))
    d[d == 0.0] = 1.0
    least = float(np.linalg.eigvalsh(k / np.outer(d, d))[0])
    if least < -1e-9:
        raise ConfigError(
            f"{what}: not positive semidefinite (a scaled eigenvalue {least:.3g} < 0: some "
            f"motion of the rod end would release energy): {accepted}"
        )
    return k


def twist_held(k6: np.ndarray, tangent: np.ndarray) -> float:
    """The twist stiffness t0^T K_tt t0 [N m/rad] of a 6x6 about a rod's axis t0."""
    t = np.asarray(tangent, dtype=np.float64)
    return float(t @ k6[3:, 3:] @ t)


def twist_coupled(k6: np.ndarray, tangent: np.ndarray) -> bool:
    """Whether a 6x6's row about a rod's axis t0 holds more than its twist: K (0, t0) is
    not k_t (0, t0), k_t = t0^T K_tt t0 (beyond 1e-9 of K's rotational scale)."""
    t = np.asarray(tangent, dtype=np.float64)
    column = k6[:, 3:] @ t
    column[3:] -= twist_held(k6, t) * t
    return bool(np.abs(column).max() > 1e-9 * max(float(np.abs(k6[3:, 3:]).max()), 1e-300))


def twist_ends(ends: RodEnds | None) -> dict[int, tuple[int, np.ndarray, float]]:
    """Node -> (the end edge's other node, its given direction, the compliance 1 / k_t
    [1/(N m)]) of every rod end whose 6x6 holds its twist (``twist_held`` > 0; its row
    about the axis uncoupled, ``twist_coupled``): held as by a clamp, in series with it."""
    out: dict[int, tuple[int, np.ndarray, float]] = {}
    if ends is None:
        return out
    for c, o, t, k6 in zip(ends.nodes, ends.other, ends.tangent, ends.stiffness, strict=True):
        k_t = twist_held(k6, t)
        if k_t > 0.0 and not twist_coupled(k6, t):
            out[int(c)] = (int(o), np.asarray(t, dtype=np.float64), 1.0 / k_t)
    return out


def end_stiffness(k6: np.ndarray, tangent: np.ndarray, EI: float, length: float) -> np.ndarray:
    """S (6 x 6): the support K (6 x 6) in series with the end edge's half-edge bending
    2 EI / l, in (u, w), the foot's rotation and twist eliminated (module docstring)."""
    t = np.asarray(tangent, dtype=np.float64)
    c = 2.0 * EI / length
    p = c * (np.eye(3) - np.outer(t, t))
    q = np.zeros((9, 9))  # (u, w, theta_f)
    q[:3, :3] = k6[:3, :3]
    q[:3, 6:] = k6[:3, 3:]
    q[6:, :3] = k6[3:, :3]
    q[3:6, 3:6] = p
    q[3:6, 6:] = -p
    q[6:, 3:6] = -p
    q[6:, 6:] = k6[3:, 3:] + p
    f = q[6:, 6:]
    vals, vecs = np.linalg.eigh(f)
    keep = vals > 1e-12 * max(float(vals.max()), c)
    inv = (vecs[:, keep] / vals[keep]) @ vecs[:, keep].T
    s = q[:6, :6] - q[:6, 6:] @ inv @ q[6:, :6]
    return 0.5 * (s + s.T)


@dataclass(frozen=True, eq=False)
class RodEnds:
    """Rod ends on 6 x 6 supports: ``nodes`` (K,) each a rod end c, ``other`` (K,) the
    other node o of its end edge, ``tangent`` (K, 3) the edge's given unit direction from
    c to o, ``stiffness`` (K, 6, 6) the support K as given (world axes) and ``series``
    (K, 6, 6) the energy's S in (u, w) (``end_stiffness``)."""

    nodes: np.ndarray
    other: np.ndarray
    tangent: np.ndarray
    stiffness: np.ndarray
    series: np.ndarray

    @classmethod
    def join(cls, parts) -> RodEnds | None:
        parts = [p for p in parts if p is not None and p.nodes.size]
        if not parts:
            return None
        return cls(*(np.concatenate([getattr(p, f) for p in parts]) for f in cls._fields()))

    @staticmethod
    def _fields() -> tuple[str, ...]:
        return ("nodes", "other", "tangent", "stiffness", "series")

    def __len__(self) -> int:
        return int(self.nodes.size)

    def check(self, n: int) -> list[str]:
        """Problems of these supports on a net of ``n`` nodes."""
        k = self.nodes.size
        if self.series.shape != (k, 6, 6) or self.tangent.shape != (k, 3):
            return [f"rod ends: stiffness of shape {self.series.shape}: must be (K, 6, 6)"]
        both = np.concatenate([self.nodes, self.other])
        bad = both[(both < 0) | (both >= n)]
        if bad.size:
            return [f"rod ends: node {int(bad[0])}: node indices must be in 0..{n - 1}"]
        return []

    def same_as(self, other: RodEnds | None) -> bool:
        return other is not None and all(
            np.array_equal(getattr(self, f), getattr(other, f)) for f in self._fields()
        )


def cross_matrix(t: np.ndarray) -> np.ndarray:
    """(K, 3, 3) [t]x of (K, 3): [t]x v = t x v."""
    out = np.zeros((len(t), 3, 3))
    out[:, 0, 1], out[:, 0, 2] = -t[:, 2], t[:, 1]
    out[:, 1, 0], out[:, 1, 2] = t[:, 2], -t[:, 0]
    out[:, 2, 0], out[:, 2, 1] = -t[:, 1], t[:, 0]
    return out


def outer(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(K, 3, 3) a b^T per row."""
    return a[:, :, None] * b[:, None, :]


def end_state(c, o, t0, S, anchor, x: np.ndarray) -> dict:
    """Per support (end node c, other node o, given direction t0, series stiffness S,
    anchor X) at x: u, d, |d|, t, t0 . t, s, a = t0 x t, w = s a, q = (u, w), S q, s',
    dw/dt, dt/dd and W = dw/dd (``catenet.terms.rodends``)."""
    u = x[c] - anchor
    d = x[o] - x[c]
    r = np.linalg.norm(d, axis=1)
    t = d / r[:, None]
    cos = np.einsum("ki,ki->k", t0, t)
    s = np.sqrt(2.0 / (1.0 + cos))
    a = np.cross(t0, t)
    q = np.concatenate([u, s[:, None] * a], axis=1)
    sq = np.einsum("kij,kj->ki", S, q)
    ds = -s / (2.0 * (1.0 + cos))
    dwdt = s[:, None, None] * cross_matrix(t0) + ds[:, None, None] * outer(a, t0)
    proj = (np.eye(3) - outer(t, t)) / r[:, None, None]
    return {"d": d, "r": r, "t": t, "c": cos, "s": s, "a": a, "q": q, "sq": sq,
            "ds": ds, "dwdt": dwdt, "proj": proj, "W": dwdt @ proj}  # fmt: skip


def end_moments(ends: RodEnds, nodes: np.ndarray, x: np.ndarray) -> np.ndarray:
    """(K, 3) the moment [N m] each 6x6 support exerts on its rod about the end node:
    the couple d x f_o of its force f_o = -W^T (S q)_w on the end edge's other node
    (``nodes`` the net's given positions: the anchors)."""
    st = end_state(ends.nodes, ends.other, ends.tangent, ends.series, nodes[ends.nodes], x)
    f_o = -np.einsum("kji,kj->ki", st["W"], st["sq"][:, 3:])
    return np.cross(st["d"], f_o)


def support_moments(net, rods, x: np.ndarray) -> np.ndarray | None:
    """(N, 3) the moment [N m] each support exerts on its rod at the rod's end node: a
    6x6 spring's (``end_moments``), a clamp's or a rotational spring's 2 kc (t x t0)
    (the couple of its energy kc |t - t0|^2, ``catenet.model.rods``); None where no
    support holds a rod end's direction. ``rods`` the scene's ``Rods`` or None."""
    x = np.asarray(x, dtype=np.float64)
    ends = None if net.springs is None else net.springs.ends
    clamps = None if rods is None or not len(rods.clamps) else rods.clamps
    if ends is None and clamps is None:
        return None
    out = np.zeros((len(x), 3))
    if ends is not None:
        np.add.at(out, ends.nodes, end_moments(ends, net.nodes, x))
    if clamps is not None:
        d = x[clamps[:, 1]] - x[clamps[:, 0]]
        t = d / np.linalg.norm(d, axis=1)[:, None]
        np.add.at(out, clamps[:, 0], 2.0 * rods.kc[:, None] * np.cross(t, rods.tangent))
    return out


def end_bending(ends: RodEnds, rods, nodes: np.ndarray, x: np.ndarray, moment, kappa) -> None:
    """Adds each 6x6 support's bending moment at its rod end to ``moment`` (N,) [N m], the
    part of its moment (``end_moments``) across the end edge (its twist about the edge
    left out), and to ``kappa`` (N,) [1/m] that over the end edge's EI (the ``rods``'
    hinge at the edge's other node); the larger where a node has one already."""
    m = end_moments(ends, nodes, x)
    d = x[ends.other] - x[ends.nodes]
    t = d / np.linalg.norm(d, axis=1)[:, None]
    across = np.linalg.norm(m - np.sum(m * t, axis=1)[:, None] * t, axis=1)
    np.maximum.at(moment, ends.nodes, across)
    h = rods.hinges
    for k, (c, o) in enumerate(zip(ends.nodes, ends.other, strict=True)):
        hit = np.flatnonzero((h[:, 1] == o) & ((h[:, 0] == c) | (h[:, 2] == c)))
        if hit.size and rods.EI[hit[0]] > 0:
            kappa[c] = max(kappa[c], across[k] / rods.EI[hit[0]])
