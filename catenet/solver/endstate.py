"""What a static equilibrium is, once found: stable, unstable (the stiffness has a
negative eigenvalue), neutral (a mode without stiffness: where the structure rests along
it is not determined), or with free nodes hanging on slack edges only; the verdict into
the Result and its warnings (docs/guide/stability.md)."""

from __future__ import annotations

import logging
from collections.abc import Sequence

import numpy as np

from catenet.model.measures import loose_nodes
from catenet.model.net import Net
from catenet.solver.diagnose import (
    bending_nodes,
    describe_neutral,
    describe_unstable,
    describe_unstable_bodies,
    has_twist,
    mode_nodes,
    unpinned_parts,
)
from catenet.solver.modal import body_frames, stable_with_bodies
from catenet.solver.result import Result
from catenet.solver.tangent import (
    DENSE,
    NEUTRAL,
    STABLE,
    UNSTABLE,
    Tangent,
    definite,
    kept_tangent,
)
from catenet.solver.workspace import Workspace

log = logging.getLogger(__name__)


def judge_stability(ws: Workspace, net: Net, x: np.ndarray, out: Result) -> None:
    """The equilibrium's stability into ``out`` (``stable``, ``diagnosis``), where it can
    be lost: free bodies, bilateral edges, or terms that are not convex (a curved
    obstacle's barrier pushes the nodes pressed on it aside: a rope draped over a
    frictionless sphere, a ball on a wire, slide off). A tension-only net with convex
    terms alone cannot lose it, but its end state may be neutral (``_neutral``)."""
    bodies = body_frames(ws.system)  # a free body may rest unstably on any net
    if not bodies and net.law.all_tension_only and all(t.convex for t in ws.system.terms):
        _neutral(ws, x, out)
    else:
        out.stable = stable_with_bodies(ws, x) if bodies else _stable(ws, x, out)
        if out.stable is False:
            out.diagnosis = diagnose_unstable(ws, x, factor=out.time)


def diagnose_unstable(
    ws: Workspace,
    x: np.ndarray,
    cables: Sequence[str] | None = None,
    cable_of_edge: np.ndarray | None = None,
    factor: float | None = None,
) -> str:
    """What makes the unstable equilibrium at x unstable, and the fix: a free body's
    rest, a tension-only net pressed on a curved frictionless surface (``_pressed``), or
    compressed bilateral edges (``describe_unstable``: a mechanism, a buckling)."""
    system = ws.system
    if system.net.law.all_tension_only and not body_frames(system):
        return _pressed(ws, x)
    return describe_unstable_bodies(system, x) or describe_unstable(
        system.stretch,
        x,
        ~system.net.fixed,
        cables,
        cable_of_edge,
        twisted=has_twist(system),
        bent=bending_nodes(system),
        factor=factor,
    )


def warn_state(ws: Workspace, net: Net, out: Result, neutral: bool = True) -> None:
    """Warnings on the equilibrium ``out``: unstable (its ``diagnosis``), neutral (unless
    not ``neutral``), or free nodes hanging on slack edges only."""
    if out.stable is False:
        log.warning(
            "the equilibrium is unstable: the stiffness matrix has negative eigenvalues "
            "(any disturbance makes the net or a body move away): %s",
            out.diagnosis,
        )
    elif out.stable is None and out.diagnosis and neutral:
        log.warning("the equilibrium is neutral: %s", out.diagnosis)
    _warn_loose(ws, net, out)


def _warn_loose(ws: Workspace, net: Net, out: Result) -> None:
    """A warning where free nodes hang on slack edges only and no other term holds them."""
    loose = loose_nodes(net, out.tension)
    for term in ws.system.terms:  # nodes that another term (a spring, contact) holds
        pattern = term.pattern() if term.edge_net is None else None
        if pattern is not None and loose.size:
            loose = np.setdiff1d(loose, pattern[0] // 3)
    if loose.size:
        log.warning(
            "%d free nodes hang on slack edges only (nodes %s%s): nothing fixes their "
            "position, the equilibrium there is not unique",
            loose.size,
            ", ".join(map(str, loose[:10])),
            " ..." if loose.size > 10 else "",
        )


def _stable(ws: Workspace, x: np.ndarray, out: Result) -> bool | None:
    """Whether the stiffness at x is positive definite, decided with the margins of
    ``catenet.solver.stability`` (None: neutral within them, or cannot tell here). A
    neutral state's mode without stiffness (dense systems) is named in ``out.diagnosis``
    where it moves nodes that do not merely hang on slack edges (``_warn_loose``)."""
    t = _named(ws, x, out)
    return True if t.verdict == STABLE else False if t.verdict == UNSTABLE else None


def _neutral(ws: Workspace, x: np.ndarray, out: Result) -> None:
    """A tension-only net's end state (its terms convex: never unstable): where its
    stiffness is not positive definite by one Cholesky factorisation (``definite``, up
    to DENSE free DOFs), its mode without stiffness named in ``out.diagnosis`` by the
    eigenvalues (``stable`` stays None). A cable on rollers whose normals leave its ends
    free to slide together (the prestress gone, it hangs doubled) ended "converged" in
    silence, and a load tilted by 1e-9 sent it 4e4 m away."""
    if ws.system.n_free <= DENSE and not definite(ws.system, x, ws.solver):
        _named(ws, x, out)


def _named(ws: Workspace, x: np.ndarray, out: Result) -> Tangent:
    """The tangent at x; a neutral one's mode named in ``out.diagnosis``."""
    t = kept_tangent(ws.system, ws.solver, x)
    if t.verdict == NEUTRAL and t.mode is not None:
        net = ws.system.net
        out.diagnosis = describe_neutral(
            t.mode, loose_nodes(net, out.tension), whole=unpinned_parts(net)
        )
    return t


def _pressed(ws: Workspace, x: np.ndarray) -> str:
    """Why a tension-only net (with balls) is unstable: its only terms that are not
    convex, the obstacles' and balls' barriers on curved surfaces, push the nodes pressed
    on them aside more than the net's tension holds them (a rope over a frictionless
    sphere, a ball on a wire, which were called stable)."""
    t = kept_tangent(ws.system, ws.solver, x)
    nodes = mode_nodes(t.mode) if t.mode is not None else np.zeros(0, np.int64)
    listed = ", ".join(map(str, nodes[:10])) + (" ..." if nodes.size > 10 else "")
    where = f"nodes {listed}" if nodes.size else "the nodes"
    names = sorted({term.label for term in ws.system.terms if not term.convex and term.label})
    on = " and ".join(names) if names else "a curved obstacle"
    return (
        f"the stiffness is negative where the net presses on {on} ({where} move most): "
        "a frictionless curved surface pushes the nodes pressed on it aside more than the "
        "net's tension holds them, and they would slide off it (a rope over the top of a "
        "sphere, a ball on a wire); give the contact friction where it takes it "
        "(obstacle[k].friction), "
        "hold those nodes (a support, a roller), or let the net rest where it is stable"
    )
