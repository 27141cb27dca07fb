"""The watch that stops a run before a free rigid body meets another body or an obstacle.

Free bodies (``catenet.case.rigid``) meet the net and planes only: a body would pass
through another free body, a ball or a fixed sphere, box, capsule or mesh. Several
bodies, and bodies beside obstacles and balls, are allowed, so that a run that never
brings them together is exact; ``Clearance`` (the scene's ``watch``) is asked after
every accepted step of a dynamic run and every equilibrium of a static one, and raises
``BodiesMeet`` (a ConvergenceError: exit 1, the result file keeping every step before) at
the first state where two of them meet or crossed since the last one:

- against a plane, exactly: the body's vertices (a box's corners, a mesh's vertices
  grown by nothing, a capsule's or a sphere's centre grown by its radius) at the new
  pose, and its centre's path since the last state (a body that went through between
  two steps); a plane holds a free body by its barrier (``catenet.terms.body_plane``),
  so this is a check that never fires, but for a body that starts through it;
- between two spheres (sphere bodies, balls, fixed spheres), exactly: their centres'
  distance against the sum of their radii, over the straight path of the centres
  between the two states (the closest approach, not only its ends);
- otherwise conservatively: the bounding spheres (about a body's centre of mass, of a
  fixed box's, capsule's or mesh's shape) over the same paths, so that a run may stop
  where the shapes themselves still have a small gap; the message says which test.

Cost: a few vector operations per pair and step.
"""

from __future__ import annotations

import math

import numpy as np

from catenet.errors import ConvergenceError


class BodiesMeet(ConvergenceError):
    """A free body meets another body or an obstacle (exit 1): ``message``, and the two
    labels and how they were found to meet."""

    def __init__(self, message: str, *about: str):
        super().__init__(message)
        self.args = (message, *about)

    def __str__(self) -> str:
        return self.args[0]


class _Sphere:
    """A bounding (or exact, ``exact``) sphere: ``centre(x)`` [m] and ``radius``."""

    def __init__(self, label: str, radius: float, exact: bool, centre, vertices=None):
        self.label, self.radius, self.exact = label, float(radius), exact
        self.centre = centre  # x -> (3,)
        self.vertices = vertices  # x -> (V, 3) points and their radius, or None


def _body_sphere(body, obs) -> _Sphere:
    """The bounding sphere of a free body about its centre of mass, and its vertices at
    a pose (exact against a plane)."""
    frame = body.frame
    c0 = body.center
    if obs.kind == "sphere":
        points, grow = np.asarray(obs.center, float)[None], float(obs.radius)
    elif obs.kind == "capsule":
        points = np.array([obs.start, obs.end], dtype=np.float64)
        grow = float(obs.radius)
    elif obs.kind == "box":
        from catenet.terms.shapes import rotation

        signs = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)])
        R = rotation(obs.axis, obs.angle)
        points = np.asarray(obs.center, float) + (signs * obs.half_size) @ R.T
        grow = 0.0
    else:  # a mesh
        points, grow = obs.surface()[0], 0.0
    arm = points - c0
    radius = float(np.linalg.norm(arm, axis=1).max()) + grow
    exact = obs.kind == "sphere"

    def centre(x):
        return frame.state(x)[0]

    def vertices(x):
        c, R = frame.pose(x)
        return c + arm @ R.T, grow

    label = f"obstacle[{body.obstacle}] (a free {obs.kind})"
    return _Sphere(label, radius, exact, centre, vertices)


def _fixed_sphere(k: int, obs) -> _Sphere | None:
    """A fixed obstacle's sphere (None: a plane, tested apart)."""
    label = f"obstacle[{k}] ({obs.kind})"
    if obs.kind == "sphere":
        c, r, exact = np.asarray(obs.center, float), float(obs.radius), True
    elif obs.kind == "capsule":
        a, b = np.asarray(obs.start, float), np.asarray(obs.end, float)
        c, r, exact = 0.5 * (a + b), 0.5 * float(np.linalg.norm(b - a)) + obs.radius, False
    elif obs.kind == "box":
        c, r, exact = np.asarray(obs.center, float), float(np.linalg.norm(obs.half_size)), False
    elif obs.kind == "mesh":
        V = obs.surface()[0]
        c = 0.5 * (V.min(axis=0) + V.max(axis=0))
        r, exact = float(np.linalg.norm(V - c, axis=1).max()), False
    else:
        return None
    return _Sphere(label, r, exact, lambda x, c=c: c)


class Clearance:
    """The watch of a scene with free bodies (module docstring): ``check(x, t)`` raises
    BodiesMeet where two of them meet at x or crossed since the last state checked
    (``when``: "t = ... s", "load factor ...", for the message)."""

    def __init__(self, case, rigid, balls):
        obstacles = case.obstacles
        self.bodies = [_body_sphere(b, obstacles[b.obstacle]) for b in rigid]
        others = []
        for b in balls:  # balls and spheres on a path: their centre is a node
            others.append(
                _Sphere(
                    f"obstacle[{b.obstacle}] (a moving sphere)",
                    b.radius,
                    True,
                    lambda x, n=b.node: np.asarray(x)[n],
                )
            )
        self.planes = []
        taken = {b.obstacle for b in rigid} | {b.obstacle for b in balls}
        for k, obs in enumerate(obstacles):
            if k in taken:
                continue
            if obs.kind == "plane":
                n = np.asarray(obs.normal, float)
                n = n / np.linalg.norm(n)
                self.planes.append((f"obstacle[{k}] (plane)", np.asarray(obs.point, float), n))
            else:
                sphere = _fixed_sphere(k, obs)
                if sphere is not None:
                    others.append(sphere)
        self.others = others
        self._last = None  # the centres at the last state checked

    def reset(self, x: np.ndarray | None = None) -> None:
        """A new run starts from x (None: unknown; the first check then tests its state
        only, not the path to it)."""
        self._last = None if x is None else self._centres(np.asarray(x))

    def _centres(self, x: np.ndarray) -> list:
        return [s.centre(x) for s in self.bodies] + [s.centre(x) for s in self.others]

    def start(self, x: np.ndarray) -> None:
        """ConfigError (exit 2) where two of them meet at the start x."""
        from catenet.errors import ConfigError

        self.reset()
        try:
            self.check(x, "the start")
        except BodiesMeet as exc:
            a, b, how = exc.args[1:]
            raise ConfigError(
                f"{a}: it meets {b} at the start ({how}): a free body meets the net only; "
                "move them apart"
            ) from None
        finally:
            self.reset()

    def __bool__(self) -> bool:
        return bool(self.bodies) and bool(self.others or self.planes or len(self.bodies) > 1)

    def check(self, x: np.ndarray, when: str) -> None:
        x = np.asarray(x)
        now = self._centres(x)
        before = self._last if self._last is not None else now
        spheres = self.bodies + self.others
        nb = len(self.bodies)
        for i in range(nb):
            for j in range(i + 1, len(spheres)):
                a, b = spheres[i], spheres[j]
                gap = _closest(before[i] - before[j], now[i] - now[j]) - a.radius - b.radius
                if gap < 0.0:
                    self._meet(a, b, when, a.exact and b.exact)
            for label, point, normal in self.planes:
                self._plane(spheres[i], label, point, normal, before[i], now[i], x, when)
        self._last = now

    def _plane(self, body, label, point, normal, c0, c1, x, when) -> None:
        crossed = min(float((c0 - point) @ normal), float((c1 - point) @ normal)) < 0.0
        points, grow = body.vertices(x)
        if crossed or float(np.min((points - point) @ normal)) - grow < 0.0:
            self._meet(body, _Sphere(label, 0.0, True, None), when, True)

    @staticmethod
    def _meet(a: _Sphere, b: _Sphere, when: str, exact: bool) -> None:
        how = (
            "they touch"
            if exact
            else "their bounding spheres touch (the shapes may still be a little apart)"
        )
        raise BodiesMeet(
            f"at {when}: {a.label} meets {b.label} ({how}); free bodies touch the net "
            "only and would pass through each other or an obstacle, so the run stops here "
            "(the result file keeps every step before): keep them apart, or make the body "
            "an obstacle on a prescribed motion",
            a.label,
            b.label,
            how,
        )


def _closest(d0: np.ndarray, d1: np.ndarray) -> float:
    """The smallest |d0 + s (d1 - d0)| over s in [0, 1]."""
    e = d1 - d0
    ee = float(e @ e)
    s = 0.0 if ee == 0.0 else min(max(-float(d0 @ e) / ee, 0.0), 1.0)
    return float(np.linalg.norm(d0 + s * e)) if math.isfinite(s) else float(np.linalg.norm(d1))
