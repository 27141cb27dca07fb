"""The floor: a plain implementation of catenet's implicit time step for a net meeting one
free box, kept as the yardstick of what one step can cost on this hardware.

The same incremental potential as catenet's (``floor_kernels.py``: tension-only linear
edges, loads, the affine box's rigidity, the log-barrier of the box seen in the body
frame, the step's inertia) and the same integrator (BDF2 on fixed steps, its first step
implicit Euler; or implicit Euler throughout), with nothing else: Numba kernels for
Phi, its gradient and its Hessian, the Hessian as a bordered band (the net's DOFs in
reverse Cuthill-McKee order, the body's 12 last) factorised by LAPACK (``dpbtrf`` and a
12 x 12 Schur complement), plain Newton with a backtracking (Armijo) line search capped
by conservative advancement against the box (no iterate has a node inside it), and the
step converged when |grad Phi| <= ``rtol`` of the load scale (the larger of |f| and the
internal forces) or Newton's step is below ``xtol``.

Its model is taken from a catenet scene's arrays (``Floor.of``): the yardstick solves
the same problem, not the same code. ``python benchmarks/peers/floor_step.py`` runs the
drop of ``mujoco_drop.toml`` with both and prints the box's momentum, the deepest
approach, the Newton iterations and the CPU time of each (``--check`` also asserts that
they agree).
"""

from __future__ import annotations

import math
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

if __name__ == "__main__":  # one thread (set before NumPy, MKL and Numba load; never on
    # import: a test process's threads are set already)
    for _var in ("MKL_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
        os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import scipy.linalg.lapack as lapack  # noqa: E402
from scipy.sparse import coo_matrix  # noqa: E402
from scipy.sparse.csgraph import reverse_cuthill_mckee  # noqa: E402

if __package__ in (None, ""):  # run as a script: the package's name all the same, so
    # that Numba's cache of the kernels is the one the package's imports read
    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from benchmarks.peers.floor_kernels import (  # noqa: E402
    box_distance,
    closest,
    hessian,
    pose,
    potential,
    step_cap,
)

ARMIJO = 1e-4
WOLFE = 0.9  # a step whose slope is still steeper than this share of the start's is lengthened
SHARE = 0.9  # conservative advancement: a node advances by this share of its gap


@dataclass
class Stats:
    steps: int = 0
    iterations: int = 0
    shifted: int = 0  # factorisations that needed a shift (an indefinite Hessian)
    closest: float = math.inf  # the smallest gap any node had at an accepted state [m]
    cpu: float = 0.0
    per_step: list[int] = field(default_factory=list)


class Floor:
    """One net and one free box, as plain arrays, and the implicit steps that advance
    them (``run``)."""

    def __init__(self, nodes, velocity, mass, fixed, force, edges, l0, ea, body, B, k, c0,
                 box, contact, kappa, dhat):  # fmt: skip
        self.x = np.ascontiguousarray(nodes, dtype=np.float64).copy()
        self.v = np.ascontiguousarray(velocity, dtype=np.float64).copy()
        self.mass = np.asarray(mass, dtype=np.float64)
        self.free = ~np.asarray(fixed, dtype=bool)
        self.f = np.ascontiguousarray(force, dtype=np.float64)
        self.edges = np.ascontiguousarray(edges, dtype=np.int64)
        self.l0 = np.ascontiguousarray(l0, dtype=np.float64)
        self.ea = np.ascontiguousarray(ea, dtype=np.float64)
        self.body = np.ascontiguousarray(body, dtype=np.int64)
        self.B = np.ascontiguousarray(B, dtype=np.float64)
        self.k = float(k)
        self.c0 = np.ascontiguousarray(c0, dtype=np.float64)
        self.box = np.ascontiguousarray(box, dtype=np.float64)
        self.contact = np.ascontiguousarray(contact, dtype=np.int64)
        self.kappa, self.dhat = float(kappa), float(dhat)
        self._order()
        self.g = np.zeros_like(self.x)

    @classmethod
    def of(cls, scene) -> Floor:
        """The floor's model of a catenet scene with one free box and no other term."""
        from catenet.terms.rigid import Rigidity
        from catenet.terms.rigid_contact import BodyContact

        net, loads = scene.net, scene.loads
        (rig,) = [t for t in scene.terms if isinstance(t, Rigidity)]
        (touch,) = [t for t in scene.terms if type(t) is BodyContact]
        shape = touch.shape
        box = np.concatenate([shape.center, shape.axes.ravel(), shape.half])
        v = np.zeros_like(net.nodes) if scene.velocity is None else scene.velocity
        frame = rig.frame
        return cls(net.nodes, v, net.mass, net.fixed, loads.external_force(net), net.edges,
                   net.rest_length, net.EA, frame.nodes, frame.B, rig.k, touch.c0, box,
                   shape.nodes, touch.kappa, touch.dhat)  # fmt: skip

    def _order(self) -> None:
        """The net's free nodes in reverse Cuthill-McKee order, then the body's four: each
        node's place ``pos`` (-1: fixed), the band's half width and its buffers."""
        n = len(self.x)
        net = self.free.copy()
        net[self.body] = False
        ids = np.flatnonzero(net)
        local = -np.ones(n, dtype=np.int64)
        local[ids] = np.arange(len(ids))
        e = self.edges[(local[self.edges[:, 0]] >= 0) & (local[self.edges[:, 1]] >= 0)]
        a = coo_matrix((np.ones(len(e)), (local[e[:, 0]], local[e[:, 1]])), shape=(len(ids),) * 2)
        perm = reverse_cuthill_mckee((a + a.T).tocsr(), symmetric_mode=True)
        pos = -np.ones(n, dtype=np.int64)
        pos[ids[perm]] = np.arange(len(ids))
        pos[self.body] = len(ids) + np.arange(4)
        self.pos = pos
        both = (pos[e[:, 0]] >= 0) & (pos[e[:, 1]] >= 0)
        width = int(np.abs(pos[e[both, 0]] - pos[e[both, 1]]).max(initial=0))
        self.p = 3 * width + 2
        self.n1 = 3 * len(ids)
        self.band = np.zeros((self.p + 1, self.n1), order="F")
        self.C = np.zeros((self.n1, 12))
        self.D = np.zeros((12, 12))
        dofs = np.full(3 * n, -1, dtype=np.int64)  # place of each DOF (-1 fixed)
        for node in np.flatnonzero(pos >= 0):
            dofs[3 * node : 3 * node + 3] = 3 * pos[node] + np.arange(3)
        self.dofs = dofs
        self.active = np.flatnonzero(dofs >= 0)

    # ---- the linear algebra -----------------------------------------------------------
    def _factor(self, shift: float):
        """Cholesky of the bordered band plus shift times the inertia's diagonal: (L, Y,
        Schur factor) or None where it is not positive definite."""
        band = self.band.copy(order="F")
        if shift > 0.0:
            band[0] *= 1.0 + shift
        L, info = lapack.dpbtrf(band, lower=1, overwrite_ab=1)
        if info != 0:
            return None
        Y, info = lapack.dtbtrs(L, self.C, uplo="L")
        if info != 0:
            return None
        S = np.tril(self.D) + np.tril(self.D, -1).T - Y.T @ Y
        if shift > 0.0:
            S[np.diag_indices(12)] += shift * np.diag(self.D)
        Sc, info = lapack.dpotrf(S, lower=1)
        if info != 0:
            return None
        return L, Y, Sc

    def _solve(self, factors, b: np.ndarray) -> np.ndarray:
        L, Y, Sc = factors
        n1 = self.n1
        z1, _ = lapack.dtbtrs(L, b[:n1, None], uplo="L")
        z2, _ = lapack.dpotrs(Sc, b[n1:, None] - Y.T @ z1, lower=1)
        x1, _ = lapack.dtbtrs(L, z1 - Y @ z2, uplo="L", trans="T")
        return np.concatenate([x1[:, 0], z2[:, 0]])

    # ---- one step ---------------------------------------------------------------------
    def _phi(self, x, w, a) -> float:
        return potential(x, self.free, self.f, self.edges, self.l0, self.ea, self.body, self.B,
                         self.k, self.c0, self.box, self.contact, self.kappa, self.dhat, w, a,
                         self.g)  # fmt: skip

    def solve(self, x, w, a, rtol: float, xtol: float, max_iter: int = 100) -> int:
        """Newton on the step's potential from x (in place): its iteration count."""
        order = np.empty(len(self.active), dtype=np.int64)
        order[self.dofs[self.active]] = self.active  # DOF of each place
        flat = x.reshape(-1)
        wf = w.reshape(-1)[order]
        self._w_band, self._w_body = wf[: self.n1], wf[self.n1 :]
        dx = np.zeros_like(x)
        mu = 0.0  # the Levenberg-Marquardt shift, relative to the Hessian's diagonal
        for it in range(1, max_iter + 1):
            phi = self._phi(x, w, a)
            g = self.g.reshape(-1)[order]
            internal = np.linalg.norm(self.g + self.f - w * (x - a) * self.free[:, None])
            scale = max(np.linalg.norm(self.f), internal)
            if os.environ.get("FLOOR_DEBUG"):
                print(it, f"{np.linalg.norm(g):.3e} mu {mu:.1e} scale {scale:.3g}")
            if np.linalg.norm(g) <= rtol * scale:
                return it - 1
            hessian(x, self.pos, self.edges, self.l0, self.ea, self.body, self.B, self.k,
                    self.c0, self.box, self.contact, self.kappa, self.dhat, w, self.band,
                    self.C, self.D, True)  # fmt: skip
            shift = mu
            while True:  # the shift grows until the factors exist and dy descends
                factors = self._factor(shift)
                if factors is not None:
                    dy = self._solve(factors, -g)
                    if np.all(np.isfinite(dy)) and float(g @ dy) < 0.0:
                        break
                shift = max(1e-6, 10.0 * shift)
                self.stats.shifted += 1
            dx.reshape(-1)[order] = dy
            alpha = min(1.0, step_cap(x, dx, self.body, self.B, self.c0, self.box,
                                      self.contact, SHARE))  # fmt: skip
            slope = float(g @ dy)
            y0 = flat[order].copy()
            cap = alpha
            alpha = self._search(x, w, a, order, y0, dy, dx, phi, slope, alpha)
            if os.environ.get("FLOOR_DEBUG"):
                print("   cap", cap, "alpha", alpha, "shift", shift)
            # Levenberg-Marquardt: the shift follows how well the quadratic model
            # predicted the full step's decrease (a slack edge turning taut, or back)
            if alpha >= 1.0:
                rho = (phi - self._phi(x, w, a)) / (-0.5 * slope)
                mu = mu / 4.0 if rho > 0.75 else (max(4.0 * mu, 1e-4) if rho < 0.25 else mu)
                mu = 0.0 if mu < 1e-8 else mu
            if alpha * np.abs(dy).max() <= xtol:
                return it
        raise RuntimeError(f"the floor's Newton did not converge in {max_iter} iterations")

    def _search(self, x, w, a, order, y0, dy, dx, phi, slope, alpha) -> float:
        """Backtracking from ``alpha`` (the cap, at most 1) until Phi falls enough
        (Armijo); a full step whose slope along dy is still steep (a slack edge taut at
        the solution: the Hessian has none of its stiffness) is lengthened fourfold at a
        time while Phi keeps falling, within the cap. x is left at the step taken."""
        flat = x.reshape(-1)
        while True:
            flat[order] = y0 + alpha * dy
            trial = self._phi(x, w, a)
            if trial <= phi + ARMIJO * alpha * slope or alpha < 1e-12:
                break
            alpha *= 0.5
        if alpha < 1.0:
            return alpha
        for _ in range(12):
            if float(self.g.reshape(-1)[order] @ dy) >= WOLFE * slope:
                break  # flat enough
            cap = step_cap(x, dx * (3.0 * alpha), self.body, self.B, self.c0, self.box,
                           self.contact, SHARE)  # fmt: skip
            longer = alpha * (1.0 + 3.0 * cap)
            flat[order] = y0 + longer * dy
            value = self._phi(x, w, a)
            if not value < trial:
                break
            alpha, trial = longer, value
        flat[order] = y0 + alpha * dy
        return alpha

    def run(self, dt: float, t_end: float, scheme: str = "bdf2", rtol: float = 1e-6,
            xtol: float = 1e-9) -> Stats:  # fmt: skip
        """Steps of dt to t_end (BDF2: its first step implicit Euler)."""
        self.stats = stats = Stats()
        x, v = self.x, self.v
        m = np.repeat(self.mass[:, None], 3, axis=1)
        prev = None
        start = time.process_time()
        for _ in range(round(t_end / dt)):
            if scheme == "bdf2" and prev is not None:
                xb = 4.0 / 3.0 * x - 1.0 / 3.0 * prev[0]
                vb = 4.0 / 3.0 * v - 1.0 / 3.0 * prev[1]
                b = 2.0 / 3.0 * dt
            else:
                xb, vb, b = x, v, dt
            a = xb + b * vb
            a[~self.free] = x[~self.free]
            w = m / b**2
            y = a.copy()
            alpha = step_cap(x, y - x, self.body, self.B, self.c0, self.box, self.contact, SHARE)
            y = x + alpha * (y - x) if alpha < 1.0 else y
            its = self.solve(y, w, a, rtol, xtol)
            stats.per_step.append(its)
            stats.iterations += its
            stats.steps += 1
            prev = (x.copy(), v.copy())
            v = (y - xb) / b
            v[~self.free] = 0.0
            x = y
            stats.closest = min(stats.closest, self.gap(x))
        stats.cpu = time.process_time() - start
        self.x, self.v = x, v
        return stats

    def gap_of(self, x, k: int) -> float:
        """The distance of contact node k (an index into ``contact``) to the box [m]."""
        c, A = pose(x, self.body, self.B)
        n, P = np.zeros(3), np.zeros((3, 3))
        center, axes, half = self.box[:3], self.box[3:12].reshape(3, 3), self.box[12:]
        X = self.c0 + (x[self.contact[k]] - c) @ A
        return float(box_distance(X, center, axes, half, n, P))

    def gap(self, x) -> float:
        """The smallest distance of a contact node to the box [m]."""
        return float(closest(x, self.body, self.B, self.c0, self.box, self.contact))

    def momentum(self) -> np.ndarray:
        return (self.mass[self.body, None] * self.v[self.body]).sum(axis=0)


SCENE = Path(__file__).resolve().parent / "mujoco_drop.toml"


def drop_scene(path: Path = SCENE):
    """The drop's catenet case (parsed) and scene."""
    import tomllib

    from catenet.case import build, parse_case

    parsed = parse_case(tomllib.loads(path.read_text()))
    return parsed, build(parsed)


def catenet_drop(dt: float, integrator: str = "bdf2", t_end: float = 0.4) -> dict:
    """catenet on the drop: the box's momentum, the closest approach, counts, CPU."""
    import dataclasses

    import catenet

    parsed, scene = drop_scene()
    settings = dataclasses.replace(catenet.Settings.of(parsed.solver), integrator=integrator,
                                   dt=dt, t_end=t_end)  # fmt: skip
    closest = [math.inf]
    (touch,) = [t for t in scene.terms if type(t).__name__ == "BodyContact"]

    def seen(state) -> None:
        closest[0] = min(closest[0], float(touch.gap(state.x).min()))

    start = time.process_time()
    result = catenet.solve(scene, settings, on_step=seen)
    cpu = time.process_time() - start
    (body,) = scene.rigid
    p = body.mass * result.v[body.frame.nodes].mean(axis=0)
    return {"momentum": p, "closest": closest[0], "steps": result.steps,
            "iterations": result.iterations, "cpu": cpu}  # fmt: skip


def floor_drop(dt: float, scheme: str = "bdf2", t_end: float = 0.4) -> dict:
    """The floor on the drop: the box's momentum, the closest approach, counts, CPU."""
    _, scene = drop_scene()
    floor = Floor.of(scene)
    stats = floor.run(dt, t_end, scheme)
    return {"momentum": floor.momentum(), "closest": stats.closest, "steps": stats.steps,
            "iterations": stats.iterations, "cpu": stats.cpu}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dt", type=float, default=0.01)
    ap.add_argument("--integrator", default="bdf2", choices=("bdf2", "implicit_euler"))
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--check", action="store_true", help="assert that the two agree")
    args = ap.parse_args(argv)
    rows: dict[str, dict] = {}
    for _ in range(args.repeats):  # the first of each compiles or loads the kernels
        for name, fn in (("floor", floor_drop), ("catenet", catenet_drop)):
            row = fn(args.dt, args.integrator)
            if name not in rows or row["cpu"] < rows[name]["cpu"]:
                rows[name] = row
    for name, r in rows.items():
        print(f"{name:8s} momentum {np.array2string(r['momentum'], precision=9)} closest "
              f"{r['closest']:.3e} m  steps {r['steps']} iterations {r['iterations']} "
              f"({r['iterations'] / r['steps']:.2f}/step)  CPU {r['cpu']:.3f} s "
              f"({1e3 * r['cpu'] / r['steps']:.2f} ms/step)")  # fmt: skip
    pf, pc = rows["floor"]["momentum"], rows["catenet"]["momentum"]
    diff = float(np.linalg.norm(pf - pc) / np.linalg.norm(pc))
    print(f"momentum difference floor - catenet: {diff:.2e} of catenet's")
    if args.check:
        assert diff < 1e-4, diff
        assert rows["floor"]["closest"] > 0 and rows["catenet"]["closest"] > 0
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
