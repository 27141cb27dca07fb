"""What a static equilibrium is, once found: stable, unstable (the stiffness has a
negative eigenvalue), neutral (a mode without stiffness: where the structure rests along
it is not determined), or with free nodes hanging on slack edges only; the verdict into
the Result and its warnings (docs/guide/stability.md)."""

from __future__ import annotations

import logging

import numpy as np

from catenet.model.measures import loose_nodes
from catenet.model.net import Net
from catenet.solver.diagnose import (
    bending_nodes,
    describe_neutral,
    describe_unstable,
    describe_unstable_bodies,
    has_twist,
    unpinned_parts,
)
from catenet.solver.modal import body_frames, stable_with_bodies
from catenet.solver.result import Result
from catenet.solver.tangent import DENSE, NEUTRAL, STABLE, UNSTABLE, Tangent, kept_tangent
from catenet.solver.workspace import Workspace

log = logging.getLogger(__name__)


def judge_stability(ws: Workspace, net: Net, x: np.ndarray, out: Result) -> None:
    """The equilibrium's stability into ``out`` (``stable``, ``diagnosis``), where it can
    be lost: free bodies, or bilateral edges. A tension-only net cannot lose it, but its
    end state may be neutral (``_neutral``)."""
    bodies = body_frames(ws.system)  # a free body may rest unstably on any net
    if not bodies and net.law.all_tension_only:
        _neutral(ws, x, out)
    else:
        out.stable = stable_with_bodies(ws, x) if bodies else _stable(ws, x, out)
        if out.stable is False:
            out.diagnosis = describe_unstable_bodies(ws.system, x) or describe_unstable(
                ws.system.stretch,
                x,
                ~net.fixed,
                twisted=has_twist(ws.system),
                bent=bending_nodes(ws.system),
                factor=out.time,
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
    ``catenet.solver.stability`` (None: neutral within them, or cannot tell here). Only
    bilateral nets can lose stability: tension-only stiffness is never negative. A
    neutral state's mode without stiffness (dense systems) is named in ``out.diagnosis``
    where it moves nodes that do not merely hang on slack edges (``_warn_loose``)."""
    t = _named(ws, x, out)
    return True if t.verdict == STABLE else False if t.verdict == UNSTABLE else None


def _neutral(ws: Workspace, x: np.ndarray, out: Result) -> None:
    """A tension-only net's end state: its mode without stiffness named in
    ``out.diagnosis`` where it has one (``stable`` stays None: not judged) and the dense
    eigenvalues serve (up to DENSE free DOFs). A cable on rollers whose normals leave
    its ends free to slide together (the prestress gone, it hangs doubled) ended
    "converged" in silence, and a load tilted by 1e-9 sent it 4e4 m away."""
    if ws.system.n_free <= DENSE:
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
