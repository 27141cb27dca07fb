"""Strikes of the net's nodes on free bodies and balls, resolved by the steps chosen by
accuracy (catenet/solver/adaptive.py).

A node that comes within a body's barrier distance dhat at a normal speed v bounces off
it: the barrier is elastic, the node of mass m is stopped where kappa b(d_min) = m v^2 / 2
and sent back in the bounce's time

    tau = 2 int_{d_min}^{dhat} dd / sqrt(v^2 - 2 kappa b(d) / m)      (``bounce_time``)

(the node alone against the body: the body is heavy, the node's cords slack as it
strikes). A step longer than a fraction of tau damps that bounce, as bdf2 damps every
mode it does not resolve, and the body receives less momentum from the strike than the
converged motion gives it: a light net thrown at a free box left the box 14-15 % slow at
the default tolerance, whose error estimate is filtered so that nodes chattering on a
body do not set the steps (docs/howto/dynamic-runs.md).

The momentum a strike exchanges lies between m v (the node stopped) and 2 m v (bounced
off). Whether that matters depends on whose momentum it is: a node that flies at a body
brings its own, m u (u its speed toward the body with the body held still), and flies
off with what the bounce leaves it; a node that a body runs into brings none, is pushed
ahead and struck again until it moves with the body, whatever its bounce (a box dropped
on a net converges at every step). Where the nodes striking a body in a step bring more
than SHARE of the tolerance times the body's momentum scale (catenet/solver/adaptive.py's
Bodies), the step is taken again to end one resolving step before the first of them (or
at half its length, where that is earlier: a strike at the step's end), and the steps
from there to the end of the bounce are tau / PER_BOUNCE (its shortest among the step's
strikes), constant and taken without the error estimate (``Strikes.cap``): steps that
vary through a stiff bounce let bdf2 gain energy (two nodes thrown at a free box gained
1 % of their energy at the default tolerance, and the run stopped).

A solid's own bounce is resolved the same way: a ball's or a free body's barrier with an
obstacle or another solid carries ``struck_by`` (``catenet.scene.movers.StruckBy``: the
solid that strikes, the other's nodes, the pair's reduced mass); its gaps are its
points', its mass the pair's, and its bounce is stepped through in tau / SOLID_BOUNCE,
the run's momentum being the solid's own (a 5 kg ball dropped 2 m on the ground lost 3 %
of its energy in a bounce at the error estimate's steps and at 16 to a bounce, 0.07 %
at 64; tests/solver/test_impacts.py).

Nodes landing on a fixed obstacle (``ground``: a plane, a fixed shape) with GROUND of
the run's largest sum of the nodes' |m v| or more (a rod or a net dropped on the floor,
not a chain's node touching down on the seabed) are stepped through their bounce the
same way, where the obstacle's barrier holds their energy above DEEPEST of its distance.
Where it cannot (the default barrier is sized for the net's loads at rest, not for an
impact), no step makes the bounce elastic: the nodes stop within the step and their
fall's energy is lost; the run says so at its end (``landings``) and names the
stiffness that holds the bounce (``impact_stiffness``, at the nodes' speed at the step's
end). A 1 m rod dropped 0.1 m flat on a plane lost 60 % of its energy at the default
barrier (82 % at tolerance 3e-4), and 60 % too at the stiffness named, its bounce
stepped over; stepped through, it rebounds at 1.387 m/s for 1.401 m/s.

``Strikes.step`` finds a step's strikes: nodes outside dhat at its start and within it at
its end, their normal speed the rate of their gap along the predictor x + s h v at s = 0
(the step's start, before the barrier acts). With fixed steps (``solver.dt``) ``Watch``
adds up what the strikes it steps over bring and warns at the end of the run where that
comes to more than SAY of a body's largest momentum.

A ball or body can also pass a strand between its nodes within one step, touching no
node in either state: neither a strike nor a contact event sees it, and a step in free
flight grows long (a 4 cm ball thrown at 15 m/s at a wire crossed it in one step of
0.146 s at the default tolerance). ``Strikes.crossing`` is the longest step in which no
ball or body within reach of the net moves more than CROSS of its width (the smallest
extent of its shape): the steps chosen by accuracy take no longer one.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from catenet.solver.scales import Bodies
    from catenet.terms import Term

log = logging.getLogger(__name__)

PER_BOUNCE = 16  # steps through a bounce: a strike's step at most tau / PER_BOUNCE
#: ... a solid's own bounce (a ball or body on an obstacle, or on another): its momentum
#: is the run's, and bdf2 at 16 steps took 3 % of a ball's energy per bounce on the ground
SOLID_BOUNCE = 64
SAY = 0.1  # strikes stepped over that carry more than SAY of a body's largest momentum
SHARE = 1.0  # strikes carrying more than SHARE x tolerance x the body's momentum scale
PROBE = 1e-6  # the predictor's share of the step at which the gap's rate is taken
CROSS = 0.25  # a ball or body near the net moves at most this share of its width a step
GROUND = 0.1  # nodes striking a fixed obstacle with this share of the run's |m v|, or more
DEEPEST = 1e-6  # ... bounce where its barrier holds their energy above this share of dhat
_U, _W = np.polynomial.legendre.leggauss(24)  # Gauss-Legendre on [-1, 1]


def _barrier(d: np.ndarray, dhat: float) -> np.ndarray:
    """b(d) = -(d - dhat)^2 ln(d / dhat) of catenet/kernels/contact.py (0 < d <= dhat)."""
    r = d - dhat
    return -r * r * np.log(d / dhat)


def bounce_time(mass: float, speed: float, kappa: float, dhat: float) -> float:
    """The time a node of ``mass`` spends within the barrier (``kappa``, ``dhat``) of a
    fixed body it meets at normal ``speed`` (module docstring); inf for no speed."""
    if not (mass > 0 and speed > 0 and kappa > 0 and dhat > 0):
        return math.inf
    energy = 0.5 * mass * speed * speed / kappa  # b(d_min)
    low, high = 0.0, dhat  # b(low) > energy >= b(high): bisection on the gap
    for _ in range(200):
        mid = 0.5 * (low + high)
        if mid <= low or mid >= high:
            break
        r = mid - dhat
        if -r * r * math.log(mid / dhat) > energy:
            low = mid
        else:
            high = mid
    d_min = high
    # d = d_min + u^2: the integrand 2 u / sqrt(f(d)) is finite at the turning point u = 0
    top = math.sqrt(max(dhat - d_min, 0.0))
    u = 0.5 * top * (_U + 1.0)
    f = speed * speed - 2.0 * kappa * _barrier(d_min + u * u, dhat) / mass
    f = np.maximum(f, 1e-300)
    return float(2.0 * 0.5 * top * np.sum(_W * 2.0 * u / np.sqrt(f)))


@dataclass(frozen=True)
class Strike:
    """The strikes of a step that matter, by the shortest bounce among them: the body's
    label, that node's normal speed [m/s] and bounce [s]."""

    label: str
    speed: float
    tau: float
    owner: int  # the body's index in the momentum scales (-1: none)
    carried: float  # the momentum the step's strikes bring (sum of m u: module docstring)
    at: float  # the share of the step at which the first of them comes within dhat
    per: int = PER_BOUNCE  # steps per bounce (SOLID_BOUNCE: a solid's own)
    who: str = "nodes"  # what struck (a solid's label)

    @property
    def longest(self) -> float:
        """The longest step that resolves the bounce."""
        return self.tau / self.per


class Strikes:
    """The strikes on a run's free bodies and balls (module docstring). ``terms``: the
    barrier terms of bodies and balls (``of``), each with its body's index in ``scales``
    (the bodies' momentum scales of catenet/solver/adaptive.py's Bodies), the nodes
    that carry its body (a free body's frame, a ball's centre) and its width; the net's
    median edge ``spacing`` (``crossing``)."""

    def __init__(
        self,
        terms: Sequence[Any],  # barriers: gap(x), kappa, dhat, nodes
        owners: Sequence[int],
        carriers: Sequence[np.ndarray],
        node_mass: np.ndarray,
        widths: Sequence[float],
        spacing: float,
    ):
        self.terms = list(terms)
        self.owners = list(owners)
        self.carriers = list(carriers)
        self.node_mass = node_mass  # each node's mass (N)
        self.widths = list(widths)  # each solid's smallest extent [m] (inf: not known)
        self.spacing = spacing  # the net's median edge [m]: how far a strand is from a node
        self.holds: list[tuple[float, float, float]] = []  # bounces: (since, until, step)
        self._last: list[tuple[np.ndarray, np.ndarray] | None] = [None] * len(self.terms)
        # a solid's own barrier: its ``struck_by`` (catenet.scene.movers.StruckBy)
        self.solids = [getattr(t, "struck_by", None) for t in self.terms]
        self.weak: dict[str, tuple[float, float, Any, str]] = {}  # ``_too_weak``

    @classmethod
    def of(
        cls, terms: Sequence[Term], bodies: Bodies | None, node_mass: np.ndarray,
        spacing: float = 0.0, ground: bool = False,
    ) -> Strikes | None:  # fmt: skip
        """The strikes of the body and ball barriers among ``terms`` (None: none);
        ``spacing``: the net's median edge; ``ground``: the fixed obstacles' too."""
        from catenet.terms.body import Ball
        from catenet.terms.contact import Obstacle
        from catenet.terms.rigid_contact import BodyContact

        heads = list(bodies.heads) if bodies is not None else []
        picked: list[Any] = []
        owners: list[int] = []
        carriers: list[np.ndarray] = []
        widths: list[float] = []
        for t in terms:
            head = None
            if (solid := getattr(t, "struck_by", None)) is not None:  # a solid's own
                head, carry = solid.head, np.asarray(solid.carry, dtype=np.int64)
                widths.append(math.inf)
            elif isinstance(t, BodyContact) and t.kappa > 0 and t.dhat > 0:
                carry = np.asarray(t.frame.nodes)
                widths.append(t.width)
            elif isinstance(t, Ball):
                carry = np.array([t.center])
                widths.append(2.0 * t.radius)
            elif ground and isinstance(t, Obstacle) and not t.moving and not t.driven:
                picked.append(t)  # a fixed obstacle: nobody's momentum (``GROUND``)
                owners.append(-1)
                carriers.append(np.zeros(0, dtype=np.int64))
                widths.append(math.inf)
                continue
            else:
                continue
            picked.append(t)
            head = int(carry[0]) if head is None else head
            owners.append(heads.index(head) if head in heads else -1)
            carriers.append(carry)
        return cls(picked, owners, carriers, node_mass, widths, spacing) if picked else None

    def crossing(self, x: np.ndarray, v: np.ndarray, h: float) -> float:
        """The longest step from (x, v) (N, 3) in which no ball or body moves more than
        CROSS of its width relative to a node that a step of ``h`` (or of that longest
        step) may bring within reach of its strands (module docstring); inf: none. The
        closing speed is bounded by the solid's fastest carrier node's plus the node's."""
        out = math.inf
        for term, carry, width in zip(self.terms, self.carriers, self.widths, strict=True):
            if not (math.isfinite(width) and width > 0.0):
                continue
            nodes = np.asarray(term.nodes)
            closing = float(np.max(np.linalg.norm(v[carry], axis=1)))
            closing = closing + np.linalg.norm(v[nodes], axis=1)
            moving = closing > 0.0
            if not moving.any():
                continue
            longest = CROSS * width / closing[moving]
            reach = closing[moving] * np.maximum(h, longest) + self.spacing
            near = term.gap(x)[moving] <= reach
            if near.any():
                out = min(out, float(longest[near].min()))
        return out

    def cap(self, t: float) -> float:
        """The longest step from t while a bounce goes on (inf: none)."""
        self.holds = [(since, until, h) for since, until, h in self.holds if until > t]
        return min((h for since, _, h in self.holds if since <= t), default=math.inf)

    def step(
        self, x: np.ndarray, v: np.ndarray, x_new: np.ndarray, h: float,
        scales: Sequence[float], tolerance: float, flow: float = math.inf,
    ) -> Strike | None:  # fmt: skip
        """The shortest bounce among the strikes that matter (module docstring) of the step
        of ``h`` from (x, v) to ``x_new`` (N, 3); None where none does. ``flow``: the
        run's largest sum of the nodes' |m v| (a fixed obstacle's strikes, ``GROUND``)."""
        out = None
        for i, (term, owner, carry) in enumerate(
            zip(self.terms, self.owners, self.carriers, strict=True)
        ):
            solid = self.solids[i]
            gap = term.gap if solid is None else (lambda y, t=term: np.atleast_1d(t.gap(y)))
            new = gap(x_new)
            last = self._last[i]  # the gaps at the last step's end: this one's start?
            old = last[1] if last is not None and np.array_equal(last[0], x) else gap(x)
            self._last[i] = (x_new.copy(), new)
            hit = (old >= term.dhat) & (new < term.dhat)
            if not np.any(hit):
                continue
            probe = gap(x + (PROBE * h) * v)[hit]
            still = v.copy()  # the body held still: the nodes' own approach
            still[carry] = 0.0
            own = gap(x + (PROBE * h) * still)[hit]
            with np.errstate(invalid="ignore"):  # (a pair beyond its reach: inf - inf)
                speed = np.maximum((old[hit] - probe) / (PROBE * h), 0.0)
                brought = np.maximum((old[hit] - own) / (PROBE * h), 0.0)
            if solid is None:
                mass = self.node_mass[np.asarray(term.nodes)[hit]]
            else:  # one solid (its gaps: its points'), its mass against the other's
                mass = np.full(int(np.count_nonzero(hit)), solid.mass)
                far = ~np.isfinite(speed)  # from beyond the pair's reach: the solids' speeds
                if far.any():
                    mine = float(np.linalg.norm(v[solid.head]))
                    theirs = np.mean(v[carry], axis=0) if len(carry) else np.zeros(3)
                    speed[far] = float(np.linalg.norm(v[solid.head] - theirs))
                    brought[far] = mine
            carried = float(np.dot(mass, brought))
            if owner >= 0 and not carried > SHARE * tolerance * scales[owner]:
                continue
            if owner < 0 and not (solid is None and carried > GROUND * flow):
                continue
            if owner < 0:  # a fixed obstacle: its nodes' speed at the step's end (uniformly
                arrive = np.maximum(speed, 2.0 * (old[hit] - new[hit]) / h - speed)  # sped)
                if self._too_weak(term, mass, arrive):
                    continue  # no bounce its barrier holds: the landing is inelastic
            with np.errstate(divide="ignore", invalid="ignore"):  # (no speed: at 0)
                at = np.clip((old[hit] - term.dhat) / (speed * h), 0.0, 1.0)
            first = float(np.min(np.nan_to_num(at, nan=0.0, posinf=0.0)))
            per, who = (PER_BOUNCE, "nodes") if solid is None else (SOLID_BOUNCE, solid.who)
            for m, s in zip(mass, speed, strict=True):
                tau = bounce_time(float(m), float(s), term.kappa, term.dhat)
                if math.isfinite(tau) and (out is None or tau / per < out.longest):
                    out = Strike(term.label, float(s), tau, owner, carried, first, per, who)
            if out is not None and out.at > first:
                out = replace(out, at=first)
        return out

    def _too_weak(self, term: Any, mass: np.ndarray, speed: np.ndarray) -> bool:
        """Whether nodes landing on the fixed obstacle ``term`` bring more energy than its
        barrier holds above DEEPEST of its distance: they stop in the step, their fall's
        energy lost (recorded for ``landings``)."""
        from catenet.terms.contact import impact_stiffness

        energy = float(np.max(0.5 * mass * speed * speed, initial=0.0))
        if not energy > term.kappa * float(_barrier(np.array([DEEPEST * term.dhat]),
                                                    term.dhat)[0]):  # fmt: skip
            return False
        seen = self.weak.get(term.label)
        fast = float(np.max(speed, initial=0.0))
        if seen is None or fast > seen[0]:
            key = getattr(term, "key", "").rsplit(".", 1)[0] or term.label
            self.weak[term.label] = (fast, impact_stiffness(energy, term.dhat), term, key)
        return True

    def advice(self) -> str:
        """The stiffness that holds the landings recorded so far ("" for none): what a
        run that creates energy as they stop is advised first."""
        return ", ".join(f"{key}.stiffness >= {needed:.3g} N/m (nodes landed on it with "
                         "more energy than its barrier holds)"
                         for _, needed, _, key in self.weak.values())  # fmt: skip

    def landings(self) -> None:
        """The warning of each fixed obstacle whose barrier was too weak for the nodes
        landing on it (``_too_weak``), said once at the end of the run."""
        for label, (fast, needed, term, key) in self.weak.items():
            log.warning(
                "nodes landed on %s at up to %.3g m/s with more energy than its barrier "
                "holds (distance %.3g m, stiffness %.3g N/m): they stopped within the step, "
                "their fall's kinetic energy lost instead of bouncing, whatever the step "
                "or tolerance; for an elastic bounce give %s.stiffness >= %.3g N/m "
                "(docs/howto/dynamic-runs.md)",
                label, fast, term.dhat, term.kappa, key, needed,
            )  # fmt: skip

    def hold(self, since: float, until: float, longest: float) -> None:
        """Steps from ``since`` to ``until`` (a bounce) at most ``longest``."""
        self.holds.append((since, until, longest))


class Watch:
    """Strikes that fixed steps (``solver.dt``) step over: what they bring (sum of m u)
    added up per body, and said at the end of the run (``report``) where it comes to
    more than SAY of the body's largest momentum: the body's momentum after them depends
    on the step. ``bodies``: the run's momentum scales (catenet/solver/adaptive.py's
    Bodies), grown here as the run goes."""

    def __init__(self, strikes: Strikes, bodies: Bodies, free: np.ndarray):
        self.strikes, self.bodies, self.free = strikes, bodies, free
        self.missed: dict[int, float] = {}  # each body's momentum in strikes stepped over
        self.first: dict[int, tuple[float, float, Strike]] = {}  # (t, h, strike)

    def step(
        self, x: np.ndarray, v: np.ndarray, x_new: np.ndarray, v_new: np.ndarray, h: float,
        t: float,
    ) -> None:  # fmt: skip
        """An accepted step of ``h`` from (x, v) at time t to (x_new, v_new), all (N, 3)."""
        strike = self.strikes.step(x, v, x_new, h, self.bodies.largest, 0.0, self.bodies.flow)
        self.bodies.saw(v_new.reshape(-1)[self.free], x_new)
        if strike is None or strike.owner < 0 or h <= strike.longest * (1.0 + 1e-9):
            return
        self.missed[strike.owner] = self.missed.get(strike.owner, 0.0) + strike.carried
        self.first.setdefault(strike.owner, (t + h, h, strike))

    def report(self) -> None:
        """The warning of each body whose strikes stepped over matter (class docstring),
        and of each fixed obstacle whose barrier was too weak for a landing."""
        self.strikes.landings()
        for owner, carried in self.missed.items():
            largest = max(self.bodies.own[owner], self.bodies.largest[owner])
            if not carried > SAY * largest:
                continue
            t, h, strike = self.first[owner]
            log.warning(
                "%s in steps of %.3g s from t = %.6g s, bringing %.3g times its "
                "largest momentum; a bounce on its barrier lasts %.3g s (at %.3g m/s), "
                "and a step longer than %.3g s (1/%d of it) damps the bounce: the body's "
                "momentum after such strikes depends on the step (give solver.dt <= %.3g s, "
                "or leave solver.dt out: steps chosen by accuracy resolve them)",
                f"nodes struck {strike.label}" if strike.who == "nodes" else f"{strike.who} met",
                h, t, carried / largest, strike.tau, strike.speed, strike.longest, strike.per,
                strike.longest,
            )  # fmt: skip
