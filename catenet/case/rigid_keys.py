"""The keys that make an ``[[obstacle]]`` a free rigid body (``mass``, ``density``,
``inertia``) and their checks, declared once for every kind that takes them (box,
capsule, mesh: ``catenet.case.shapes``; sphere: ``catenet.case.obstacles``); the bodies
are built by ``catenet.scene.rigid`` (``catenet.case.rigid`` turns them into builder calls)."""

from __future__ import annotations

import numpy as np

from catenet.case.keys import Checker, Context, key, real


def _check_inertia(ck: Checker, v, path: str, ctx: Context):
    from catenet.terms.rigid import inertia_problem

    need = "must be [[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]] or 3 principal moments"
    rows = v
    if isinstance(v, (list, tuple)) and len(v) == 3 and not isinstance(v[0], (list, tuple)):
        try:
            rows = np.diag([float(c) for c in v]).tolist()
        except (TypeError, ValueError):
            return ck.bad(path, v, need)
    try:
        tensor = np.array(rows, dtype=np.float64)
    except (TypeError, ValueError):
        return ck.bad(path, v, need)
    if tensor.shape != (3, 3):
        return ck.bad(path, v, need)
    why = inertia_problem(tensor)
    if why is not None:
        return ck.bad(path, v, f"must be an inertia tensor about the centre of mass: {why}")
    return tuple(tuple(r) for r in tensor.tolist())


def mass_key():
    return real(None, gt=0, write="given", unit="kg", doc="a free rigid body of this mass")


def density_key():
    return real(None, gt=0, write="given", unit="kg/m^3", doc="a free rigid body of this density")


def inertia_key():
    return key(
        _check_inertia,
        "3 x 3 symmetric positive definite [kg m^2] (or 3 principal moments)",
        None,
        write="given",
        shown="from the shape",
        unit="kg m^2",
        doc="free body: inertia about its centre of mass, body axes",
    )


class FreeKeys:
    """What the free-body keys (``mass``, ``density``, ``inertia``) mean on a table."""

    mass: float | None  # the keys of the obstacle kinds that mix it in
    density: float | None
    inertia: tuple | None
    history: tuple | None  # the prescribed motion's factor, which a free body refuses

    @property
    def free(self) -> bool:
        """A free rigid body (six degrees of freedom)."""
        return self.mass is not None or self.density is not None

    def _check_free(self, ck: Checker, path: str) -> None:
        if self.mass is not None and self.density is not None:
            ck.add(f"{path}.density = {self.density!r}: give mass or density, not both")
        if self.inertia is not None and not self.free:
            ck.add(f"{path}.inertia: belongs to a free body: give mass or density with it")
        if self.free and self.history is not None:
            ck.add(
                f"{path}.history: a free body moves as the forces on it say; history "
                "scales a prescribed motion (drop mass and density for one)"
            )
