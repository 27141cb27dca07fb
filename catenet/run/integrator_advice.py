"""What a dynamic run is told about its integrator after it: an integrator that removed much
of the energy on its own (the runner logs it as a warning, as ``catenet.run.advice``'s).
Newmark in contact is refused before the run (``catenet.case.timing.newmark_refused``):
measured on the drop of benchmarks/peers/mujoco_drop.toml (a 12 kg box dropped onto a
net, 23.8 kg m/s at impact), at rho_inf = 0.8 the box leaves with 21, 37, 29 kg m/s at
dt = 1, 0.5, 0.25 ms and up to 2.5 kg m/s sideways in a symmetric scene (implicit Euler:
15.0, 15.6, 15.8; bdf2 16.2 at 0.3 ms); a net dropped onto a fixed box fails its steps at
first contact at any rho_inf (docs/howto/dynamic-runs.md)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from catenet.solver.energy import COLUMNS, at_roundoff
from catenet.solver.result import Outcome

if TYPE_CHECKING:
    from catenet.case.parse import Case


#: A snatch is warned where the largest tension after a snap is this many times the
#: largest before it, or more: the snap made the run's peak (a wire that went slack once
#: on its heaving vessel, whose drift then raised its largest tension to 1.09 times that
#: before, converged to 0.25 % between tolerances 3e-3 and 1e-4: not warned).
SNATCH_RISE = 1.2

#: The integrator's own loss (a share of the run's largest energy) that earns a warning,
LOSS_WARN = 0.2
#: ... or a share of the motion's: the run's largest kinetic energy and what damping,
#: drag and friction took,
MOTION_WARN = 0.15
#: ... where the motion holds this share of the run's largest energy or more (a rope
#: pushed slowly by a moving obstacle, its motion 1e-5 of its stretch, was told that the
#: integrator "removed 1079 % of the motion's energy ... 0.0 % of the largest").
MOTION_MATTERS = 1e-3


def integrator_loss(case: Case, result) -> str | None:
    """The warning of a dynamic run to a time (not to rest), with contact, undamped or
    ending at t_end before it rests (a transient: damped as the user asked, not as the
    step does), whose integrator removed more than LOSS_WARN of the run's largest energy
    on its own (the balance's ``numerical`` column: not damping, not friction), or more
    than MOTION_WARN of the motion's energy, its largest kinetic energy and what
    damping, drag and friction took: its motion after an impact, a rebound, peak forces,
    depend on the step. Measured on the drop of benchmarks/peers/mujoco_drop.toml
    (benchmarks/drop.py): implicit Euler at the default 10 ms loses 49 % and the box
    leaves with 47 % too little momentum; at 2.5 ms 22 % and 15 %; bdf2 at 10 ms loses
    10.5 % (the net's ringing, which it cannot resolve) with the box within 1 %. The
    motion's share tells where the run's largest energy is mostly held still: a roof net
    under a gust at fixed bdf2 steps of 20 ms loses 49 % of its motion's energy (19 % of
    its largest, its stretch) and its peak tension comes out 20 % low
    (tests/run/test_integrator_loss.py); the 2 t mass dropped on
    benchmarks/cable_net_kn.toml lost 18 %, its peak rope tension 7 % off. Steps chosen
    by accuracy hold the integrator's energy where no barrier touches
    (catenet/solver/adaptive.py): the gust at the default tolerance loses 4 %, the drop
    12 % (in contact), the safety net and tennis net of benchmarks/ 1.6 and 2.6 %, the
    thrown net and the capture under 1 %; the moorings of configs/water/ 0.3 to 7 % at
    their dt, where drag takes far more than the motion holds at any time (against the
    largest kinetic energy alone, a chain in waves over 300 s had lost 11 times it)."""
    solver = case.solver
    energy, scale = result.energy, result.energy_scale
    if solver.method != "dynamic" or solver.t_end == "rest" or energy is None:
        return None
    relaxed = getattr(result, "outcome", None) != Outcome.REACHED_T_END  # (came to rest)
    if not (case.obstacles or solver.self_contact) and solver.damping > 0 and relaxed:
        return None  # the paper's damped runs to rest: implicit Euler's loss is its method
    if not scale > 0.0:
        return None
    lost = -float(energy[-1]) / scale
    took = max(float(energy[COLUMNS.index("dissipated")]), 0.0)  # damping, drag, friction
    motion = float(getattr(result, "energy_motion", float("nan"))) + took
    noise = at_roundoff(float(energy[-1]), scale)
    matters = motion > MOTION_MATTERS * scale and not noise  # (quasi-static: no motion)
    moved = -float(energy[-1]) / motion if matters else 0.0
    if not (lost > LOSS_WARN or moved > MOTION_WARN):
        return None
    name = solver.integrator
    if solver.tolerance is not None:
        steps = f"steps chosen by solver.tolerance = {solver.tolerance:g}"
        remedy = "a smaller solver.tolerance"
    else:
        steps = f"solver.dt = {solver.dt:g} s"
        remedy = "a smaller solver.dt"
    if name == "implicit_euler":
        more = (
            ", or steps chosen by accuracy (solver.tolerance)" if solver.tolerance is None else ""
        )
        remedy = (
            "solver.integrator = 'bdf2' (second order: it keeps what implicit Euler damps), "
            + remedy
            + more
        )
    share = f"{lost:.0%} of the run's largest energy"
    if not lost > LOSS_WARN:
        share = (
            f"{moved:.0%} of the motion's energy (its largest kinetic energy, in its centre "
            "of mass's frame where nothing holds the net, and what damping, drag and "
            f"friction took; {lost:.1%} of the largest)"
        )
    if landed := getattr(result, "landed", ""):  # the landings' stiffness, not the step
        return (
            f"the integrator ({name}, {steps}) removed {share} on its own (the energy "
            "balance's 'numerical' part): nodes landed on a barrier too weak to hold them "
            "and stopped within the step (the warning above), which no step or tolerance "
            f"changes; give {landed}"
        )
    return (
        f"the integrator ({name}, {steps}) removed {share} on "
        "its own (the energy balance's 'numerical' part; not damping or friction): the "
        "motion, a rebound after an impact and the peak forces depend on the step here; "
        f"check with {remedy} (docs/howto/dynamic-runs.md)"
    )


def snatch(case: Case, result, terms: Sequence) -> str | None:
    """The warning of a dynamic run to a time whose largest tension came after a rope went
    slack and snapped taut again (``catenet.model.peaks``: a snap), SNATCH_RISE times the
    largest before it or more (the snatch's rise, not the slow loads', made the peak),
    where nothing damps the snapped ropes' axial waves (``material.axial_damping`` 0 on
    every snapped edge). A snatch's peak rides on those
    waves, which the steps do not resolve, and grows as they shrink: the chain lying on
    the seabed of tests/solver/test_energy_steps.py, its fairlead pulled 5 m and stopped,
    peaks at 81.4 to 84.6 kN at the default tolerance (round-off alone moves it: its
    end moved by 8e-11 m, the threads given), 87.5, 91.0 and 93.3 kN at fixed bdf2
    steps of 2, 1 and 0.5 ms; with axial damping of 3 % at its lowest axial wave (c = 1e6
    N s) 71.3 kN at the default and 71.9 kN at 1e-3."""
    solver, peaks = case.solver, getattr(result, "peaks", None)
    if solver.method != "dynamic" or solver.t_end == "rest" or peaks is None:
        return None
    if not np.isfinite(peaks.snap_time) or not len(peaks.tension):
        return None
    top = int(np.argmax(peaks.tension))
    largest, when = float(peaks.tension[top]), float(peaks.tension_time[top])
    if not (when >= peaks.snap_time and largest >= SNATCH_RISE * max(peaks.before_snap, 0.0)):
        return None
    snapped = peaks.snapped
    for term in terms:
        if term.name == "axial_damping" and np.all(term.rate[snapped] > 0.0):
            return None  # the snapped ropes' waves are damped: the peak converges
    return (
        f"the largest tension ({largest:.6g} N at t = {when:.4g} s) came after a rope went "
        f"slack and snapped taut again (first at t = {peaks.snap_time:.4g} s; "
        f"{int(snapped.sum())} edges snapped), {largest / max(peaks.before_snap, 1e-300):.3g} "
        "times the largest before it, and nothing damps the ropes' axial waves but the "
        "integrator: a snatch's peak rides on waves the steps do not resolve, and grows as "
        "they shrink. Give the ropes their axial damping (material.axial_damping, sized at "
        "the rope's lowest axial wave: docs/howto/dynamic-runs.md), or take this peak as a "
        "lower bound"
    )
