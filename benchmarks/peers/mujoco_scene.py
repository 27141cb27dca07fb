"""What catenet and MuJoCo share in their side-by-side runs (``mujoco_capture.py``): the
scene as plain arrays, the stiffness mapping, the box's geometry, the measures taken and
the search for the largest stable step. NumPy only: the MuJoCo process
(``mujoco_net.py``) imports it too, and the tests run it without MuJoCo.

The scene (a dict, written as JSON for the MuJoCo process):

- ``nodes`` (N, 3) [m], ``velocity`` (N, 3) [m/s], ``mass`` (N,) [kg] (every lumped
  mass: the cords' share and any point mass), ``fixed`` (N,) bool;
- ``edges`` (M, 2), ``EA`` (M,) [N], ``rest_length`` (M,) [m]: catenet's tension-only
  edges (see ``tendon``);
- ``radius`` [m]: the cords' radius (MuJoCo's node spheres), ``gravity`` (3,) [m/s^2];
- ``box``: ``center``, ``half_size``, ``axes`` (3, 3, the body axes as columns),
  ``mass`` [kg], ``inertia`` (3, 3) [kg m^2] in the body axes, ``velocity`` and
  ``angular_velocity`` (world frame), ``friction`` (Coulomb coefficient; 0: none);
- ``dt``, ``t_end`` [s], ``samples``: the times at which the box's state is recorded.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


def tendon(EA: float, rest_length: float) -> dict:
    """MuJoCo's spatial tendon with catenet's edge law.

    catenet's edge pulls with T = EA (l - r) / r for l > r and is slack (T = 0) for
    l <= r: a linear, tension-only spring of stiffness EA / r. A MuJoCo spatial tendon
    with ``stiffness`` k and a dead-band ``springlength`` [lo, hi] exerts k (l - hi) for
    l > hi, nothing for lo <= l <= hi and k (lo - l) below lo (XML reference,
    tendon/spatial/springlength). So k = EA / r, springlength = [0, r]: the same law
    for every l >= 0 (a tendon's length is never negative).
    """
    if not (EA > 0 and rest_length > 0):
        raise ValueError(f"tendon: EA = {EA!r} and rest length {rest_length!r} must be > 0")
    return {"stiffness": EA / rest_length, "springlength": (0.0, float(rest_length))}


def tendon_force(EA: float, rest_length: float, length: float) -> float:
    """The tension [N] the tendon of ``tendon(EA, rest_length)`` carries at ``length``."""
    t = tendon(EA, rest_length)
    lo, hi = t["springlength"]
    if length > hi:
        return t["stiffness"] * (length - hi)
    if length < lo:
        return -t["stiffness"] * (lo - length)
    return 0.0


def edge_force(EA: float, rest_length: float, length: float) -> float:
    """catenet's tension-only linear law: EA (l - r) / r when taut, else 0."""
    return EA * (length - rest_length) / rest_length if length > rest_length else 0.0


def box_inertia(mass: float, half_size) -> np.ndarray:
    """A solid box's principal moments [kg m^2] about its centre: m (b^2 + c^2) / 3 with
    the half sizes a, b, c (m (B^2 + C^2) / 12 in full lengths)."""
    a, b, c = (float(h) for h in half_size)
    return mass / 3.0 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])


def box_distance(points, center, axes, half_size) -> np.ndarray:
    """Signed distance [m] of points (P, 3) to a box's surface (negative inside): the
    box centred at ``center`` with body axes ``axes`` (columns) and ``half_size``."""
    local = (np.asarray(points, float) - np.asarray(center, float)) @ np.asarray(axes, float)
    q = np.abs(local) - np.asarray(half_size, float)
    outside = np.linalg.norm(np.maximum(q, 0.0), axis=1)
    inside = np.minimum(q.max(axis=1), 0.0)
    return outside + inside


def penetration(points, center, axes, half_size, radius: float = 0.0) -> float:
    """How deep [m] the deepest of the points, each a sphere of ``radius``, is inside the
    box: max(0, radius - distance); 0 when none touches it."""
    if len(points) == 0:
        return 0.0
    d = box_distance(points, center, axes, half_size)
    return float(max(0.0, radius - float(d.min())))


def quaternion(R) -> np.ndarray:
    """The unit quaternion (w, x, y, z) of a rotation matrix (MuJoCo's order)."""
    R = np.asarray(R, float)
    w = math.sqrt(max(0.0, 1.0 + R[0, 0] + R[1, 1] + R[2, 2])) / 2.0
    x = math.sqrt(max(0.0, 1.0 + R[0, 0] - R[1, 1] - R[2, 2])) / 2.0
    y = math.sqrt(max(0.0, 1.0 - R[0, 0] + R[1, 1] - R[2, 2])) / 2.0
    z = math.sqrt(max(0.0, 1.0 - R[0, 0] - R[1, 1] + R[2, 2])) / 2.0
    x = math.copysign(x, R[2, 1] - R[1, 2])
    y = math.copysign(y, R[0, 2] - R[2, 0])
    z = math.copysign(z, R[1, 0] - R[0, 1])
    q = np.array([w, x, y, z])
    return q / np.linalg.norm(q)


def rotation(q) -> np.ndarray:
    """The rotation matrix of a unit quaternion (w, x, y, z)."""
    w, x, y, z = np.asarray(q, float) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def momentum_error(p, reference, scale: float | None = None) -> float:
    """|p - reference| / scale of a momentum (3,); the scale defaults to |reference|
    (1 if that is 0)."""
    p, ref = np.asarray(p, float), np.asarray(reference, float)
    if scale is None:
        scale = float(np.linalg.norm(ref))
    return float(np.linalg.norm(p - ref) / (scale if scale > 0 else 1.0))


def extrapolate(coarse, fine):
    """First-order Richardson extrapolation 2 fine - coarse of a quantity computed at
    steps h and h / 2 by a first-order integrator (implicit Euler, MuJoCo's
    ``discrete`` and ``implicitfast``): its error falls from O(h) to O(h^2)."""
    return 2.0 * np.asarray(fine, float) - np.asarray(coarse, float)


def momentum_scale(momenta) -> float:
    """The scale errors in the box's momentum are measured against: the largest |p| over
    a run's samples (the momentum at the end may be near zero)."""
    m = np.linalg.norm(np.asarray(momenta, float).reshape(-1, 3), axis=1)
    return float(m.max()) if len(m) else 0.0


@dataclass(frozen=True)
class Outcome:
    """One run at a step: ``finite`` (every state finite, no blow-up), the box's final
    momentum (3,) [kg m/s], and the wall and CPU seconds it took."""

    finite: bool
    momentum: np.ndarray
    seconds: float = 0.0
    cpu_seconds: float = 0.0


def stable(outcome: Outcome, reference, tol: float, scale: float | None = None) -> bool:
    """Stable at a step: finite, and the box's final momentum within ``tol`` times
    ``scale`` (default: |reference|) of the fine-step answer ``reference``."""
    if not outcome.finite:
        return False
    return momentum_error(outcome.momentum, reference, scale) <= tol


@dataclass(frozen=True)
class Bisection:
    """The largest stable step found: ``stable`` (the largest step that passed),
    ``unstable`` (the smallest that failed above it; inf: none failed up to the cap),
    and every step tried with its outcome, in the order tried."""

    stable: float
    unstable: float
    tried: list


def largest_stable_step(
    run: Callable[[float], Outcome],
    reference,
    tol: float,
    *,
    start: float,
    cap: float,
    scale: float | None = None,
    ratio: float = 1.15,
    floor: float = 0.0,
    limit: int = 40,
) -> Bisection:
    """The largest step dt <= cap at which ``run(dt)`` is stable (``stable``), to a
    bracket [stable, unstable] with unstable / stable <= ``ratio``.

    From ``start`` the step doubles until a run fails or the cap is reached (or, if
    ``start`` fails, halves until one passes, down to ``floor``), then the bracket is
    halved geometrically. ``scale``: as in ``stable``. Stability need not be
    monotone in the step (a run may pass at a larger step by luck): the answer is a
    stable step with a failing one at most ``ratio`` above it, not the largest of all.
    """
    tried: list = []

    def ok(dt: float) -> bool:
        out = run(dt)
        tried.append((dt, out))
        return stable(out, reference, tol, scale)

    lo, hi = start, math.inf
    while not ok(lo):
        hi, lo = lo, lo / 2.0
        if lo < floor or len(tried) >= limit:
            raise ValueError(f"largest_stable_step: no stable step from {start:g} down to {lo:g}")
    while hi == math.inf and lo < cap and len(tried) < limit:
        dt = min(2.0 * lo, cap)
        if ok(dt):
            lo = dt
        else:
            hi = dt
            break
    while hi < math.inf and hi / lo > ratio and len(tried) < limit:
        mid = math.sqrt(lo * hi)
        if ok(mid):
            lo = mid
        else:
            hi = mid
    return Bisection(lo, hi, tried)
