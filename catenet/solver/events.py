"""Contact events of a run whose steps are chosen by accuracy (catenet/solver/adaptive.py):
a first touch (an obstacle's, a ball's or a free body's barrier that held no energy at the
step's start holds some at its end) and a release (the other way round), landed on rather
than stepped over.

A contact term's barrier is active where a gap is below its activation distance dhat, so
whether it touches is whether its energy is positive. After a converged step from (x, v)
to x_new, a term whose state changed had its event somewhere in the step: its time is
found by bisection along the predictor x + s h v (s in [0, 1]: where the motion would go
without the contact, the time of a first touch within dhat) and along the step's path,
the parabola x + s h v + s^2 (x_new - x - h v) (the predictor bent to meet the step's
end: a release), as the first s where any term's state differs from the step's start
(BISECTIONS halvings: to 2^-BISECTIONS of the step). A step whose event lies at s in
(EARLY, LATE) is tried again with length s h (its end the first state in contact, or the
last one touching), so that the next step starts at the event: the error estimate then
sees the impact from its first instant rather than a step that straddles it, and a peak
force is resolved from the touch on. An event in the first EARLY or last 1 - LATE of a
step is the step's start or end already: the step is taken as it is (no step is cut to a
sliver, and a step landed on its event is not cut again).

Terms on a prescribed motion are judged at their pose at the step's end (the events of a
moving obstacle are found to within its motion over the step).
"""

from __future__ import annotations

import logging
from collections.abc import Sequence

import numpy as np

from catenet.terms import Term

log = logging.getLogger(__name__)

BISECTIONS = 12  # the event's time to 2^-12 of the step
EARLY = 0.05  # an event in the step's first 5 %: at its start already
LATE = 0.95  # ... in its last 5 %: at its end already


def contact_terms(terms: Sequence[Term]) -> tuple[Term, ...]:
    """The terms with a barrier (an activation distance dhat > 0): obstacles, balls,
    free bodies' contact with the net and with each other, self-contact."""
    return tuple(t for t in terms if float(getattr(t, "dhat", 0.0) or 0.0) > 0.0)


DEEP = 1e-3  # nodes within this share of a barrier's distance are pressed deep into it


def deep_contact(terms: Sequence[Term], x: np.ndarray) -> str:
    """Where the nodes at x are pressed deepest into a keyed barrier, within DEEP of its
    distance: a sentence naming it and what holds them farther out (a net dropped on a
    fixed sphere sank to 1e-9 of its barrier's distance, and the run stopped blaming the
    tolerance); else ''."""
    deepest = None
    for term in contact_terms(terms):
        key, dhat = getattr(term, "key", ""), float(getattr(term, "dhat", 0.0))
        gap, pairs = getattr(term, "gap", None), getattr(term, "distances", None)
        if not key or (gap is None and pairs is None):
            continue
        try:
            if gap is not None:
                least = float(np.min(gap(x), initial=np.inf))
            elif pairs is not None:  # the strands' self-contact: its pairs' gaps
                r2 = float(getattr(term, "gap_r", 0.0))  # (capsules: less 2 r)
                least = float(np.min(pairs(x, DEEP * dhat + r2), initial=np.inf)) - r2
        except (TypeError, ValueError):
            continue
        if least < DEEP * dhat and (deepest is None or least / dhat < deepest[0]):
            deepest = (least / dhat, least, dhat, key, term.label, gap is None)
    if deepest is None:
        return ""
    _, least, dhat, key, label, strands = deepest
    longer = f"e.g. {key} = {100.0 * dhat:.3g}, 100x"
    if strands:  # the strands' barrier (no stiffness key: it follows the loads)
        return (
            f"strands are pressed to {least:.3g} m of each other, within a thousandth of "
            f"the self-contact's distance ({dhat:.3g} m, {key}): its barrier is too weak "
            "for the motion that brings them together, and its forces' round-off at that "
            f"depth exceeds the loads; a longer distance ({longer}) holds them farther apart"
        )
    stiff = key.removesuffix(".distance") + ".stiffness"
    return (
        f"nodes are pressed to {least:.3g} m of {label}, within a thousandth of its "
        f"barrier's distance ({dhat:.3g} m, {key}): the barrier is too weak for the "
        "motion that brings them there (a net landing on it), and its forces' round-off "
        f"at that depth exceeds the loads; a stiffer barrier ({stiff}) or a longer "
        f"distance ({longer}) holds them farther out"
    )


class Events:
    """The contact state of a run's barrier terms (``contact_terms``) and the events of
    its steps (module docstring): ``landing`` after a converged step, ``take`` once a
    step is accepted. ``touches`` and ``releases`` count the events landed on."""

    def __init__(self, terms: Sequence[Term], x: np.ndarray, pull: np.ndarray | None = None):
        self.terms = contact_terms(terms)
        self.state = self._state(x)
        self.before = self.state  # the accepted state's before it (``touching``)
        self.touches = 0
        self.releases = 0
        self.pull = pull  # gravity's acceleration on the free nodes (None: no gravity)

    def _state(self, x: np.ndarray) -> tuple[bool, ...]:
        """Whether each term touches at x (a barrier energy that is not 0: a node inside,
        whose energy is not finite, touches too)."""
        return tuple(not t.energy(x) <= 0.0 for t in self.terms)

    def _first(self, x: np.ndarray, dx: np.ndarray, bend: np.ndarray | None) -> float | None:
        """The first share s of the path x + s dx (+ s^2 bend) where the contact state
        differs from the step's start (to 2^-BISECTIONS), None where it does not at s = 1."""
        end = x + dx if bend is None else x + dx + bend
        if self._state(end) == self.state:
            return None
        low, high = 0.0, 1.0  # the state at low is the start's, at high it is not
        for _ in range(BISECTIONS):
            mid = 0.5 * (low + high)
            at = x + mid * dx if bend is None else x + mid * dx + mid * mid * bend
            if self._state(at) == self.state:
                low = mid
            else:
                high = mid
        return high

    def landing(self, x: np.ndarray, v: np.ndarray, x_new: np.ndarray, h: float) -> float | None:
        """The share s of the step of ``h`` from (x, v) to ``x_new`` at which its first
        contact event lies, where the step should be tried again with length s h; None
        where it has none to land on (none, or one at its start or end). A touch is
        looked for along the predictor x + s h v (the barrier stops the step's own path
        at its end, where it is already inside dhat) and, from a state touching nothing,
        along it bent by gravity, x + s h v + (s h)^2 / 2 ``pull`` (a rod falling 55 ms
        onto a plane touched 10 ms before the straight predictor said; gravity moves no
        free node against another); a release along the step's path."""
        if not self.terms:
            return None
        found = [
            self._first(x, h * v, None),
            self._first(x, h * v, x_new - x - h * v),
        ]
        if self.pull is not None and not any(self.state):  # a first touch, accelerated
            found.append(self._first(x, h * v, 0.5 * h * h * self.pull))
        shares = [f for f in found if f is not None]
        if not shares or not EARLY < min(shares) < LATE:
            return None
        share = min(shares)
        log.info("contact event at %.3g of the step of %.3g s: landed on", share, h)
        return share

    def touching(self, x: np.ndarray) -> list[Term]:
        """The barriers that touch at x (N, 3) or at either of the last two accepted
        states (bdf2's step reaches back over both)."""
        now = self._state(x)
        return [t for t, a, b, c in zip(self.terms, self.before, self.state, now, strict=True)
                if a or b or c]  # fmt: skip

    def take(self, x: np.ndarray) -> None:
        """The accepted step's end (x) is the contact state from now on; the events it
        ended counted."""
        state = self._state(x)
        self.touches += sum(b and not a for a, b in zip(self.state, state, strict=True))
        self.releases += sum(a and not b for a, b in zip(self.state, state, strict=True))
        self.before, self.state = self.state, state
