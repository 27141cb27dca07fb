"""A scene: what the solver solves, built from a case file (``catenet.case.build``) or in
Python, with one builder that owns the contact policy (``catenet.scene.contact``):

    scene = Scene.of(net, loads).with_obstacle(Box(...), friction=0.3)
    result = catenet.solve(scene, method="dynamic", dt=1e-3, t_end=1.0)

A scene is frozen: each ``with_`` returns a new one. The same scene from a case file and
from the builder is the same computation: the case's obstacles go through the same
``with_obstacle`` policy (``catenet.case.obstacles``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from catenet.model.net import Loads, Net
from catenet.scene.contact import ACCURACY, Contact, Reach, Shown, obstacle_terms

if TYPE_CHECKING:
    from catenet.scene.shapes import Shape
    from catenet.terms.base import Term


def extent(net: Net) -> float:
    """The diagonal of the net's bounding box [m]: a scene's length scale by default."""
    return float(np.linalg.norm(net.nodes.max(axis=0) - net.nodes.min(axis=0)))


@dataclass(frozen=True, eq=False)
class Scene:
    """A net, its loads and the energy terms the scene adds to the stretching of its
    edges (obstacles, friction, bodies' contacts; ``catenet.terms``), with:

    - ``probe``: the node whose z-deflection is "delta" (``probe_auto``: none was named,
      the summary reports the free node that moves most), ``size``: the length scale L
      of delta/L and of the contact policy's widest barrier;
    - ``velocity`` (N, 3): initial velocities (None: at rest);
    - ``bodies``: moving spheres (``catenet.case.bodies.Body``), whose centres are among
      the net's last nodes; ``rigid``: free bodies, four nodes each after them
      (``catenet.case.rigid.FreeBody``);
    - ``cables``: the cable of every edge (``catenet.case.kinds.cables.CableIndex``, None:
      no cables); ``sets``, ``at_nodes``, ``names``: node sets, the node of each point
      load along a cable, named nodes;
    - ``cases``: the load cases and combinations (``LoadCase``);
    - ``obstacles``: (index, shape, Contact) of each obstacle the builder added (the
      index: its ``obstacle[k]`` in messages and in a case file);
    - ``case``: the case file's case it was built from (None: built in Python);
      ``coarsen(factor)``: the same scene with every edge ``factor`` times longer, or
      None (a nested start, ``catenet.solver.nested``; None: it cannot be coarsened).
    """

    net: Net
    loads: Loads = field(default_factory=Loads)
    terms: tuple[Term, ...] = ()
    probe: int = 0
    size: float = 1.0
    velocity: np.ndarray | None = None
    bodies: tuple[Any, ...] = ()
    rigid: tuple[Any, ...] = ()
    cables: Any = None
    sets: Mapping[str, Any] = field(default_factory=dict)
    at_nodes: Mapping[int, int] = field(default_factory=dict)
    names: Mapping[str, int] = field(default_factory=dict)
    probe_auto: bool = False
    cases: tuple[Any, ...] = ()
    obstacles: tuple[tuple[int, Shape, Contact], ...] = ()
    case: Any = None
    coarsen: Callable[[float], Scene | None] | None = None

    @classmethod
    def of(
        cls,
        net: Net,
        loads: Loads | None = None,
        *,
        probe: int | None = None,
        size: float | None = None,
        velocity: ArrayLike | None = None,
    ) -> Scene:
        """A scene of ``net`` under ``loads`` (None: none); ``probe`` (None: the free
        node that moves most), ``size`` (None: the net's bounding-box diagonal),
        ``velocity`` (N, 3) initial velocities (None: at rest)."""
        v = None if velocity is None else np.asarray(velocity, dtype=np.float64)
        if v is not None and v.shape != net.nodes.shape:
            raise ValueError(f"velocity: shape {v.shape}, the net's nodes are {net.nodes.shape}")
        return cls(
            net,
            Loads() if loads is None else loads,
            probe=0 if probe is None else int(probe),
            size=extent(net) if size is None else float(size),
            velocity=v,
            probe_auto=probe is None,
        )

    def with_terms(self, *terms: Term) -> Scene:
        """This scene with more energy terms."""
        return dataclasses.replace(self, terms=(*self.terms, *terms))

    def with_obstacle(
        self,
        shape: Shape,
        *,
        distance: float | None = None,
        accuracy: float = ACCURACY,
        stiffness: float | None = None,
        friction: float = 0.0,
        slip: float | None = None,
        velocity: Sequence[float] | None = None,
        angular_velocity: Sequence[float] | None = None,
        history: Sequence[Sequence[float]] | None = None,
    ) -> Scene:
        """This scene with an obstacle of ``shape`` (``catenet.scene.shapes``: Plane,
        Sphere, Box, Capsule, Cylinder, Mesh) acting on every free node of the net, by
        the contact policy (``catenet.scene.contact``: the keys of an ``[[obstacle]]``
        table, the same defaults). Raises ConfigError where a node starts inside it."""
        contact = Contact(
            distance=distance,
            accuracy=accuracy,
            stiffness=stiffness,
            friction=friction,
            slip=slip,
            velocity=None if velocity is None else tuple(map(float, velocity)),
            angular_velocity=None
            if angular_velocity is None
            else tuple(map(float, angular_velocity)),
            history=None if history is None else tuple((float(t), float(f)) for t, f in history),
        )
        return self.with_contact(shape, contact)

    def with_contact(
        self, shape: Shape, contact: Contact, index: int | None = None, shown: Shown | None = None
    ) -> Scene:
        """``with_obstacle`` with the policy's keys as a Contact; ``index``: the
        obstacle's number in messages (``obstacle[k]``; None: the next), ``shown``: how
        they show a value (a case file's: as written)."""
        k = len(self.obstacles) if index is None else int(index)
        reach = Reach.of(self.net, self.loads, self.size)
        args = (f"obstacle[{k}]", shape, contact, reach, self.net)
        terms = obstacle_terms(*args) if shown is None else obstacle_terms(*args, shown)
        return dataclasses.replace(
            self, terms=(*self.terms, *terms), obstacles=(*self.obstacles, (k, shape, contact))
        )

    def coarser(self, factor: float) -> Scene | None:
        """The same scene with every edge length times ``factor`` and fewer nodes, or
        None (``coarsen``)."""
        return None if self.coarsen is None else self.coarsen(factor)
