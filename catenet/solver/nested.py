"""The nested start (grid continuation) of a static run: the same case solved on a coarser
net (every edge length ``factor`` times longer), its displacements carried along each
cable onto the fine net (``catenet.model.transfer``), Newton on the fine net from there.

From a flat, unstressed net the default (stretched) start takes more Newton iterations
the finer the net (the paper's n = 34 net: 7, 8, 10 and 12 at 1 cm, 2 mm, 1 mm and
0.2 mm edges), each a factorisation of the whole net. The coarse net's equilibrium is
within its discretisation error of the fine one, inside Newton's quadratic basin: 3
iterations on the fine net at every size, after 7 on a net of about COARSE_DOFS.

``solver.start`` chooses (``settings.STARTS``): "stretched" the default start always; "nested"
this start wherever it applies (else bad input naming why); "auto" this start for a
static run of a net of at least NESTED_DOFS free DOFs that starts flat and unstressed
(the stretched start's nets), where the coarse solve pays for itself; the default start
elsewhere (smaller nets, the paper's 1 cm nets, everything with obstacles or bodies).
It needs a net discretised by an edge length (``Scene.coarser``: a square net, a graph
whose cables give ``edge_length``), and a static run from the reference positions (not a
given start state, a restart, a load case from the base state, or form finding).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from catenet.errors import ConfigError
from catenet.model.net import Net
from catenet.solver.start import start_state, unstressed

if TYPE_CHECKING:
    from catenet.scene import Scene
    from catenet.solver.settings import Settings

NESTED_DOFS = 70_000  # auto: nets of this many free DOFs and more start nested
COARSE_DOFS = 10_000  # the coarse net has about this many free DOFs ...
MIN_FACTOR = 2.0  # ... its edges at least this many times longer than the fine net's


@dataclass(frozen=True)
class NestedStart:
    """What the coarse solve of a nested start cost: the coarse net's edge length over
    the fine net's (``factor``), its free DOFs, its Newton iterations and seconds."""

    factor: float
    dofs: int
    iterations: int
    seconds: float

    def describe(self) -> str:
        """The summary's words for it, e.g. "after 7 on the net at 10x the edge length
        (10047 DOF)"."""
        return (
            f"after {self.iterations} on the net at {self.factor:.3g}x the edge length "
            f"({self.dofs} DOF)"
        )


def free_dofs(net: Net) -> int:
    """Free DOFs of a net: three per node that is not a support."""
    return 3 * int(np.count_nonzero(~net.fixed))


def coarse_factor(scene: Scene, settings: Settings, given_start: bool) -> float | None:
    """How much longer the coarse net's edges are, or None for the default start
    (module docstring). Raises ConfigError where ``solver.start = "nested"`` cannot
    apply, naming why."""
    mode = settings.start
    if mode == "stretched" or settings.method == "dynamic":
        return None
    forced = mode == "nested"

    if given_start or scene.coarsen is None:
        return None  # the given state (a load case's base state); a net without its case
    if scene.terms:
        if forced:
            raise ConfigError(
                'solver.start = "nested": a net with obstacles, bodies, rods or self-contact has '
                'no nested start; use "auto" or "stretched"'
            )
        return None
    net, loads = scene.net, scene.loads
    dofs = free_dofs(net)
    if not forced:
        if dofs < NESTED_DOFS:
            return None
        x = start_state(net, loads, None, 1.0 / settings.steps)
        force = loads.external_force(net, 1.0 / settings.steps)[~net.fixed]
        if not (np.any(force) and unstressed(net, x)):
            return None  # not the flat, unstressed start the coarse net is for
    return max(MIN_FACTOR, float(f"{dofs / COARSE_DOFS:.2g}"))  # 10x, not 10.18x


def coarse_scene(scene: Scene, factor: float, forced: bool) -> Scene | None:
    """The coarse scene (``scene.coarser(factor)``); None (or, forced, ConfigError)
    where the case has no edge length to lengthen."""
    coarse = scene.coarser(factor)
    if coarse is None and forced:
        raise ConfigError(
            'solver.start = "nested": needs a net discretised by an edge length '
            '(geometry.kind = "square_net", or a graph whose cables give edge_length) '
            'that names no node by an index refinement changes; use "auto" or "stretched"'
        )
    return coarse
