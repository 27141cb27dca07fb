"""Stability verdicts, decided the same way on every machine: one module for the static
load path of ``run``, ``sweep``, load cases and the state ``modes`` starts from.

A state's verdict comes from its tangent stiffness K, compared DOF by DOF with the scale
of its own diagonal (``System.stiffness``, D): with S = D^(-1/2), the eigenvalues of S K S
are read against a margin, ``MARGIN``, far above round-off (a few 1e-16 x the condition)
and far below the negative stiffness of a physical instability (a compressed pinned strut
pushes its joint sideways by N / l, that is its strain times its axial stiffness):

- "unstable": the least eigenvalue is below -MARGIN (round-off cannot make that: the
  eigenvalues of S K S carry errors of a few 1e-14);
- "stable":   it is above +POSITIVE (an inextensible hanging chain's sway is a few
  1e-11 of its axial stiffness: stable, and said so);
- "neutral":  between them (a zero mode: a free node on slack edges, an untensioned
  straight chain), neither stable nor unstable; never called unstable. Only the exit
  code hangs on "unstable", so only its margin must be far from round-off.

Small systems (up to ``DENSE`` free DOFs) take the dense eigenvalues; larger ones the
inertia of K + MARGIN D and K - POSITIVE D from the symmetric-indefinite factorisation.

A loaded path is a **collapse** when it loses stability on its way, wherever Newton then
ends (that end depends on round-off, and so differs between processors; the verdict must
not). ``PathJudge`` follows the load steps of ``catenet.solver.loadsteps.continuation``:

1. its start (supports in place, load factor 0) is unstable and loads act on it: a
   collapse at load factor 0, unless the start was only a guess (compression alone,
   no edge in tension balancing it: a bilateral cable given on its chord with slack) and
   the path ends at a stable state with every bilateral edge in tension (the cable sagged
   into its catenary); struts prestressed against guys that fold into tension collapsed;
2. a load step ends at an unstable equilibrium: a collapse beyond the step's start (the
   last step too: wherever round-off lets Newton go from there, the verdict is the same);
3. a load step from a stable state is not reversible: unloaded back to its start's load
   factor, the net does not come back (within ``RETURN`` of the step's move): the step is
   halved, down to 1/2**``REFINE``, and a step that stays irreversible as it shrinks
   passes a limit point or a bifurcation (a snap-through, a fold). A stable elastic path
   is reversible; each judged step costs one more solve, on nets with bilateral edges
   only (a step whose unloading finds no equilibrium is not judged by this test);
4. a bilateral edge that carries no tension at the end of a step has turned through more
   than ``ROTATION`` in it: a member that fell;
5. a load step from a neutral state (a mode without stiffness) turns bilateral edges
   through more than ``ROTATION``: the loads drive a mechanism (a frame on pinned feet
   swung about them), when the step halved down to 1/2**``REFINE`` of itself still
   does. A bilateral cable or net given straight at its rest length sags from such a
   state too, but its sag shrinks with the load (as its cube root) and its edges turn
   far less than ROTATION at a sixty-fourth of any load it carries; a mechanism's swing
   does not shrink;
6. a load step from a neutral state moves along its zero modes, and the members' forces
   at its end push that move on (a negative geometric stiffness along it): a mechanism
   that compression drives, wherever Newton ends (``catenet.solver.mechanism``); or the
   members its loads compress to first order push along a part of those modes that the
   members follow without stretching (a finite mechanism, ``compressed_across``).

The first three are decided with the margins above; the last three by angles and forces
far from any threshold in the models that trigger them, and by tensions read against the
solve's own accuracy (``_slack``): an edge that carries nothing in the exact answer
carries round-off either way after Newton, never a share of the load.
"""

from __future__ import annotations

import logging
import math
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from catenet.errors import ConvergenceError
from catenet.solver.diagnose import DRIVES, _shown, describe_neutral, joint_turn, mode_nodes
from catenet.solver.tangent import (  # (the verdicts and margins, with ``tangent``)
    NEUTRAL,
    POSITIVE,
    STABLE,
    UNSTABLE,
    Tangent,
    _scale,
    kept_tangent,
)

if TYPE_CHECKING:
    from catenet.model.net import Loads, Net
    from catenet.solver.workspace import Workspace

log = logging.getLogger(__name__)

SOFT = 1e-9  # a given geometry's modes this soft (100 MARGIN) carry a drift (``drifts``)
RETURN = 0.05  # unloaded, a reversible step comes back within this share of its move
RETURN_FLOOR = 1e-6  # ... or within this share of the structure's size
FLAT = 1e-3  # ... or on one flat set with it: the potential within this share of the
FLAT_POINTS = 9  # step's change of potential at these points of the way between them
REFINE = 6  # a jumping step is halved down to 1/2**REFINE of itself before it is a collapse
ROTATION = math.pi / 4  # a bilateral edge without tension that turns more than this fell
GUESS = 1e-3  # a start whose tensions are all below this share of a node's load is a guess
ROUNDOFF_STRAIN = 1e-6  # a start strained less than this is at its rest length (round-off)
FLIP = 0.75 * math.pi  # a guessed start's edge turned more than this folded over, no sag
IMPERFECTION = 1e-3  # a collapse followed through leaves an unstable state this far
TAUT = 100.0  # a bilateral edge is in tension above this many times the solve's accuracy
NOISE = 64.0  # ... and above this many round-offs of its axial force, EA eps |x| / l0
EPS = float(np.finfo(np.float64).eps)

DRIVEN = "the structure is a mechanism under these loads"  # rule 5's verdict
COLLAPSED, POST_COLLAPSE = "collapsed", "post-collapse"


class CollapseError(ConvergenceError):
    """A static load path lost its stability (``PathJudge``): ``factor`` the load factor
    where, ``nodes`` the free nodes that move most in the collapse."""

    def __init__(
        self,
        message: str,
        *,
        factor: float,
        nodes: ArrayLike = (),
        verdict: str = COLLAPSED,
        **kwargs: Any,
    ):
        super().__init__(message, **kwargs)
        self.verdict = verdict  # COLLAPSED, or UNSTABLE: an unloaded unstable start
        self.factor = float(factor)
        self.nodes = np.asarray(nodes, dtype=np.int64)


def _bilateral(net: Net) -> np.ndarray:
    return ~np.asarray(net.law.tension_only, dtype=bool) & np.ones(net.n_edges, bool)


def _directions(net: Net, x: np.ndarray) -> np.ndarray:
    e = x[net.edges[:, 1]] - x[net.edges[:, 0]]
    length = np.linalg.norm(e, axis=1)
    unit: np.ndarray = e / np.where(length > 0.0, length, 1.0)[:, None]
    return unit


class PathJudge:
    """Follows the stability of a static load path (see the module docstring). Inactive
    (every call a no-op) for nets whose edges are all tension-only or that carry free
    bodies (``catenet.solver.modal.stable_with_bodies`` judges those)."""

    def __init__(
        self, ws: Workspace, loads: Loads, *, post_collapse: bool = False, rtol: float = 1e-8
    ):
        from catenet.solver.modal import body_frames

        self.ws = ws
        self.rtol = rtol  # the solves' relative accuracy: what a tension is known to
        self.net = ws.system.net
        self.loads = loads
        self.post_collapse = post_collapse
        bilateral = _bilateral(self.net)
        self.active = bool(np.any(bilateral)) and not body_frames(ws.system)
        # friction makes a path irreversible by itself: no unloading test there
        self.reversible = not any(t.lagged for t in ws.system.terms)
        # the nodes a collapse moves: those of bilateral edges (struts); a tension-only
        # edge's nodes may hang anywhere once it is slack
        self.bilateral = bilateral
        self.struts = np.zeros(self.net.n_nodes, bool)
        self.struts[self.net.edges[bilateral].ravel()] = True
        self.struts &= ~self.net.fixed
        extent = np.ptp(self.net.nodes, axis=0) if self.net.n_nodes else np.zeros(3)
        self.size = float(np.linalg.norm(extent)) or 1.0
        self.start_unstable = False
        self.guessed = False
        self.loaded = True
        self.start_x: np.ndarray | None = None
        self.top = 0.0  # the largest nodal load at load factor 1
        self._modes: tuple[np.ndarray, np.ndarray] | None = None  # a state's zero modes
        self._seen: list[tuple[np.ndarray, Tangent]] = []  # the last two states judged
        self._start: tuple[np.ndarray, Tangent] | None = None  # the start's (``start_tangent``)
        self.collapsed: str = ""  # what happened, once a collapse was followed through

    # --- what each state says ----------------------------------------------------------
    def tangent(self, x: np.ndarray) -> Tangent:
        """The tangent's verdict at x, kept for the last two states asked (a step's end is
        the next step's start, and each is asked again by the unloading test) and for the
        path's start (``start_tangent``'s verdict, whatever was asked since)."""
        if self._start is not None and np.array_equal(self._start[0], x):
            return self._start[1]
        for seen, verdict in self._seen:
            if np.array_equal(seen, x):
                return verdict
        verdict = kept_tangent(self.ws.system, self.ws.solver, x)
        self._seen = [(np.array(x, copy=True), verdict), *self._seen[:1]]
        return verdict

    def begin(self, x: np.ndarray, loaded: bool) -> None:
        """The path's start (supports in place, load factor 0)."""
        if not self.active:
            return
        self.loaded = loaded
        t = self.start_tangent(x)
        self.start_unstable = t.verdict == UNSTABLE
        # a start stressed in compression only (no edge in tension to balance it: a
        # bilateral cable given on its chord with slack, or straight at its rest length
        # with its nodes moved by round-off) is a guess, not a structure: no tension
        # above GUESS of the largest load on a node
        tension = self.ws.system.tension(x)
        load = self.ws.potential(self.loads, 1.0).f_free
        top = float(np.max(np.abs(load), initial=0.0))
        self.guessed = not bool(np.any(tension > GUESS * top))
        self.top = top
        self.start_x = x.copy()

    def start_tangent(self, x: np.ndarray) -> Tangent:
        """The tangent at a loaded path's start x, neutral where its verdict is round-off's
        (``_at_rest_length``; unloaded, the given geometry is the verdict's subject)."""
        self._start = None
        t = self.tangent(x)
        if self.loaded and self._at_rest_length(x, t):
            t = replace(t, verdict=NEUTRAL)
            self._seen = [(s, t if np.array_equal(s, x) else v) for s, v in self._seen]
        self._start = (np.array(x, copy=True), t)
        return t

    def step(self, prev: np.ndarray, f0: float, f1: float, x1: np.ndarray, last: bool) -> str:
        """The load step from the equilibrium ``prev`` at ``f0`` to ``x1`` at ``f1``:
        "" when it keeps the path stable, else why it does not (one sentence)."""
        if not self.active or self.collapsed:
            return ""
        if self.start_unstable:
            if last and self._ends_taut(x1):
                return ""
            if not last:
                return ""  # decided at the end: a slack bilateral cable sags into tension
            return self.why_start()
        if not self.loaded:
            return ""  # unloaded from a stable start: the end's own verdict
        t1 = self.tangent(x1)
        if t1.verdict == UNSTABLE:  # from a stable start: it lost its stability on the way
            return f"the equilibrium at load factor {f1:.6g} is unstable"
        angles = self._angles(prev, x1)
        slack = self._slack(x1)
        swung = np.flatnonzero(self.bilateral & (angles > ROTATION))
        if swung.size and self.tangent(prev).verdict == NEUTRAL:
            deg = math.degrees(angles[swung].max())
            return (
                f"{DRIVEN}: at load factor {f0:.6g} "
                f"it has a mode without stiffness, and the loads drive it: bilateral edges "
                f"{_shown(swung)} turned through up to {deg:.0f} degrees by load factor "
                f"{f1:.6g}"
            )
        pushed = self._pushed(prev, f0, f1, x1)
        if pushed:
            return pushed
        turned = np.flatnonzero(slack & (angles > ROTATION))
        if turned.size:
            deg = math.degrees(angles[turned].max())
            return (
                f"bilateral edges {_shown(turned)} turned through up to {deg:.0f} degrees "
                f"between load factors {f0:.6g} and {f1:.6g} and carry no tension: a member "
                "fell"
            )
        return ""

    def beyond(self, x: np.ndarray) -> np.ndarray:
        """Where a path followed through its collapse (solver.post_collapse) goes on
        from x: an unstable x moved along its unstable mode by IMPERFECTION of the
        structure's size (an equilibrium that is unstable only by symmetry, a straight
        strut split in two, stays put under Newton and under the motion alike), else x
        itself (where the mode is not known: large systems)."""
        t = self.tangent(x)
        if t.verdict != UNSTABLE or t.mode is None:
            return x
        top = float(np.max(np.abs(t.mode)))
        return x if top == 0.0 else x + (IMPERFECTION * self.size / top) * t.mode

    def neutral_mode(self, x: np.ndarray) -> str:
        """What the mode without stiffness at x is (``describe_neutral``), where x is
        neutral and its mode known (dense systems), else ""."""
        if not self.active or (t := self.tangent(x)).verdict != NEUTRAL or t.mode is None:
            return ""
        mode = t.mode.reshape(-1)[self.ws.system.free_dofs]
        load = self.ws.potential(self.loads, 1.0).f_free
        share = abs(float(mode @ load)) / max(
            float(np.linalg.norm(mode) * np.linalg.norm(load)), 1e-300
        )
        where = "driven" if share > DRIVES else "failed"
        return describe_neutral(t.mode, np.zeros(self.net.n_nodes, bool), where)

    def _pushed(self, prev: np.ndarray, f0: float, f1: float, x1: np.ndarray) -> str:
        """Rule 6 (``catenet.solver.mechanism``): from a neutral start, a step along its
        zero modes that the compressed members push on."""
        from catenet.solver.mechanism import (
            FAR,
            PUSH,
            compressed_across,
            elastic,
            pushed_along,
            zero_modes,
        )

        system = self.ws.system
        start = self.tangent(prev)
        if start.verdict != NEUTRAL or start.zero is None:
            return ""  # (dense systems only: their zero modes are known)
        if self._modes is None or not np.array_equal(self._modes[0], prev):
            zero = start.zero if start.all_zero else None
            modes = zero_modes(system, prev, _scale(system), POSITIVE, zero)
            self._modes = (np.array(prev, copy=True), modes)
        load = abs(f1) * self.top
        modes = self._modes[1]
        g = self._g(f1, prev)
        move, push, held = pushed_along(system, modes, prev, x1, size=self.size, load=load)
        if push < -PUSH and self.tangent(x1).verdict != STABLE:  # (a stable end holds it)
            what = "its compressed members push its nodes"
        elif move and abs(held) < PUSH and move > FAR * elastic(system, modes, prev, g):
            what = "nothing holds its nodes, which moved"  # (a strut folded unstressed)
        elif compressed_across(system, modes, prev, g, load=load) < -PUSH:
            return (
                f"{DRIVEN}: at load factor {f0:.6g} it has a mode without stiffness along "
                "which its members turn without stretching, and the members the loads "
                "compress push along it: the state that carries them is unstable from "
                "their first share on"
            )
        else:
            return ""
        return (
            f"{DRIVEN}: at load factor {f0:.6g} it has a mode without stiffness, and the "
            f"loads drive it: {what} {move:.3g} m along that mode by load factor {f1:.6g}"
        )

    def _g(self, factor: float, x: np.ndarray) -> np.ndarray:
        """The out-of-balance force at x under the loads at ``factor`` (free DOFs)."""
        g: np.ndarray = self.ws.potential(self.loads, factor).evaluate(x).g.copy()
        return g

    def drifts(self, x0: np.ndarray, x1: np.ndarray) -> bool:
        """Whether the unloaded equilibrium x1 that Newton found from the given geometry
        x0 lies along x0's zero modes farther than ALONG of the size: Newton drifted
        along a mechanism (a frame on pinned feet turned 160 degrees about them from a
        start moved by round-off), and the path is judged from x0 instead."""
        from catenet.solver.mechanism import ALONG

        t = self.tangent(x0)  # its modes below SOFT: round-off can call such a state stable
        if t.lam is None or t.vecs is None or not np.any(t.lam <= SOFT):
            return False
        modes = np.linalg.qr(t.vecs[:, t.lam <= SOFT])[0]
        step = (x1 - x0).reshape(-1)[self.ws.system.free_dofs]
        return bool(np.linalg.norm(modes @ (modes.T @ step)) > ALONG * self.size)

    def turned(self, a: np.ndarray, b: np.ndarray) -> float:
        """The largest angle [rad] a bilateral edge turns through from a to b (0: none)."""
        return float(np.max(self._angles(a, b)[self.bilateral], initial=0.0))

    def balanced(self, x: np.ndarray, rtol: float) -> bool:
        """Whether x is an equilibrium at load factor 0 (the given geometry under its
        prestress alone), to rtol of its force scale or its round-off floor."""
        ev = self.ws.potential(self.loads, 0.0).evaluate(x)
        return ev.gnorm <= max(rtol * ev.scale, ev.floor)

    def reversible_from(self, prev: np.ndarray) -> bool:
        """Whether a step from ``prev`` is checked by unloading (``returns``): a loaded,
        active path not yet collapsed, from a stable state (a neutral one, a flat net
        that its load tightens, has no unique state to return to)."""
        if not self.active or self.collapsed or not self.loaded or not self.reversible:
            return False
        return self.tangent(prev).verdict == STABLE

    def returns(self, prev: np.ndarray, back: np.ndarray, x1: np.ndarray) -> bool:
        """Whether unloading x1 to the step's start factor came ``back`` to ``prev``: its
        largest distance from prev, over the nodes of bilateral edges, is within RETURN of
        the step's largest move there (or RETURN_FLOOR of the structure's size). A stable
        path is reversible; a step over a limit point or a bifurcation is not (the snapped
        or folded state stays)."""
        on = self.struts
        moved = float(np.max(np.linalg.norm((x1 - prev)[on], axis=1), initial=0.0))
        away = float(np.max(np.linalg.norm((back - prev)[on], axis=1), initial=0.0))
        return away <= max(RETURN * moved, RETURN_FLOOR * self.size)

    def flat(
        self, prev: np.ndarray, back: np.ndarray, x1: np.ndarray, f0: float, f1: float
    ) -> bool:
        """Whether the unloaded state ``back`` that did not come back to ``prev`` lies on
        one flat set of equilibria with it: along the straight way between them (back
        itself included) the potential at the start factor f0 stays within FLAT of the
        step's own change of potential (from prev to x1 at f1), or its round-off, of
        prev's. Tension-only members at their rest length leave such a set (a roof truss
        whose tie is at rest length when unloaded came back 0.1 mm aside, its tie slack
        all the way); a snapped state lies below it, beyond a barrier (a shallow truss
        inverted)."""
        at_f0, at_f1 = self.ws.potential(self.loads, f0), self.ws.potential(self.loads, f1)
        start = at_f0.evaluate(prev)
        step = abs(at_f1.evaluate(x1).phi - at_f1.evaluate(prev).phi)
        level = max(start.phi_tol, FLAT * step)
        way = (prev + s * (back - prev) for s in np.linspace(0.0, 1.0, FLAT_POINTS)[1:])
        return all(abs(at_f0.evaluate(x).phi - start.phi) <= level for x in way)

    def why_jump(self, f0: float, f1: float, prev: np.ndarray, back: np.ndarray) -> str:
        away = float(np.max(np.linalg.norm((back - prev)[self.struts], axis=1), initial=0.0))
        return (
            f"the step from load factor {f0:.6g} to {f1:.6g} passes a limit point or a "
            f"bifurcation: unloaded again it stays {away:.3g} m away from where it started "
            "(a snap-through or a fold)"
        )

    def why_start(self) -> str:
        from catenet.solver.diagnose import bending_nodes, describe_unstable, has_twist

        start = self.start_x if self.start_x is not None else self.net.nodes
        system = self.ws.system
        what = describe_unstable(
            system.stretch,
            start,
            ~self.net.fixed,
            twisted=has_twist(system),
            bent=bending_nodes(system),
        )
        if not self.loaded:
            return f"the given geometry is an unstable equilibrium under its prestress: {what}"
        return f"the given geometry is unstable under its prestress, so any load folds it: {what}"

    def _at_rest_length(self, x: np.ndarray, t: Tangent) -> bool:
        """Whether the unstable verdict ``t`` at x is round-off's: every bilateral edge
        within ROUNDOFF_STRAIN of its rest length (nine digits of given coordinates strain
        a short edge by 1e-8 to 1e-7; unstressed, K has no negative eigenvalue). It is
        then judged as its exact, neutral geometry would be (rules 5 and 6). (A start
        stable by round-off tension stays stable: its steps are judged as steps from a
        stable state, a member that fell taken again by the motion.)"""
        net = self.net
        e = x[net.edges[:, 1]] - x[net.edges[:, 0]]
        strain = np.abs(np.linalg.norm(e, axis=1) / np.asarray(net.rest_length) - 1.0)
        return t.verdict == UNSTABLE and bool(np.all(strain[self.bilateral] <= ROUNDOFF_STRAIN))

    def _ends_taut(self, x: np.ndarray) -> bool:
        """Whether x is stable with every bilateral edge in tension, from a start that was
        only a guess (``guessed``: compression alone, nothing in tension balancing it). A
        prestressed system (struts against guys) folded into tension is a collapse."""
        if not self.guessed or np.any(self._slack(x)):
            return False
        start = self.start_x if self.start_x is not None else self.net.nodes
        if np.any(self._angles(start, x)[self.bilateral] > FLIP):
            return False  # a strut or an arch turned over its pins, no sag
        return self.tangent(x).verdict != UNSTABLE

    def _slack(self, x: np.ndarray) -> np.ndarray:
        """The bilateral edges that carry no tension at x that counts: at most TAUT times
        the solves' accuracy (rtol of the largest |tension|) or NOISE round-offs of their
        axial force (EA eps |x| / l0), what an edge that carries nothing in the exact
        answer carries after Newton, of either sign, on any processor."""
        tension = self.ws.system.tension(x)
        top = float(np.max(np.abs(tension), initial=0.0))
        size = float(np.max(np.abs(x), initial=0.0))
        noise = NOISE * EPS * size * np.asarray(self.net.EA) / self.net.rest_length
        slack: np.ndarray = self.bilateral & (tension <= np.maximum(TAUT * self.rtol * top, noise))
        return slack

    def _angles(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        cos = np.einsum("ij,ij->i", _directions(self.net, a), _directions(self.net, b))
        angles: np.ndarray = np.arccos(np.clip(cos, -1.0, 1.0))
        return angles

    def moving_nodes(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """The free nodes that move most from a to b (within half of the largest move)."""
        move = np.linalg.norm(b - a, axis=1)
        move[self.net.fixed] = 0.0
        top = float(move.max()) if move.size else 0.0
        if top <= 0.0:
            return np.zeros(0, np.int64)
        nodes = np.flatnonzero(move >= 0.5 * top)
        return nodes[np.argsort(-move[nodes])]

    def unstable_nodes(self, x: np.ndarray) -> np.ndarray:
        """The free nodes of negative own stiffness at x, else of its least mode (dense)."""
        from catenet.solver.diagnose import unstable_nodes

        own = unstable_nodes(self.ws.system.stretch, x, ~self.net.fixed)
        if own.size:
            return own
        t = self.tangent(x)
        return own if t.mode is None else mode_nodes(t.mode)


def describe_collapse(
    judge: PathJudge, why: str, factor: float, nodes: np.ndarray, far: np.ndarray | None = None
) -> str:
    """The collapse's message: where, what, which nodes, and the fix; ``far``: the state
    the collapse moved toward, where a rigid joint's turn about a rod that does not twist
    is named."""
    from catenet.solver.diagnose import bending_nodes

    where = f"nodes {_shown(nodes)}" if nodes.size else "the net"
    bent = bending_nodes(judge.ws.system, ends=True)  # a strut's end slides as it bows
    fix = (
        f"; {where} move most. The structure is a mechanism or loses its stability "
        "under these loads (a chain of pinned struts, an unbraced joint, a snap-through, "
        "guys going slack): brace or fix those nodes, prestress the guys, make a strut one "
        "edge, or lower the load"
    )
    if why.startswith(DRIVEN):  # no load is small enough: hold the mechanism
        fix = (
            f"; {where} move most. Any load that drives a mechanism moves it until it "
            "lines up with the load: brace or fix those nodes, or hold the mode (clamp "
            "the feet of a frame, add a support or an edge across it)"
        )
    elif bent is not None and nodes.size and bool(np.all(bent[nodes])):  # rods that bend
        fix = (
            f"; {where} move most. The loads exceed a buckling (limit) load of the "
            "structure as modelled, its rods' bending stiffness (material.EI) included "
            "(a rod beyond its Euler load, guys going slack, a snap-through): lower the "
            "load, or brace those nodes, stiffen the rods or prestress the guys"
        )
    terms = judge.ws.system.terms
    if any(t.name == "joints" for t in terms):  # rigid joints
        fix += (
            "; or a frame turning at a rigid joint about the axis of a rod that does not "
            "twist (no GJ, or its other end free to turn: a frame on pinned feet, or on "
            "one clamped foot, swings out of its plane): hold it across its plane "
            "([[supports.roller]]), clamp its feet or give its rods GJ"
        )
    fix = "" if judge.start_unstable else joint_turn(terms, far) + fix
    kept = "The start" if judge.start_unstable else "The last stable state"
    if not judge.loaded:
        return f"{why}. {kept} is kept as the result"
    return (
        f"the load path collapses beyond load factor {factor:.6g}: {why}{fix}. {kept} is "
        "kept as the result; solver.post_collapse = true follows the path through to the "
        "far equilibrium and labels it post-collapse"
    )
