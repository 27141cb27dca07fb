"""What a dynamic run is told about its integrator: before it, newmark's known failure in
impacts; after it, an integrator that removed much of the energy on its own (the runner
logs them as warnings, as ``catenet.run.advice``'s)."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from catenet.case.parse import Case


#: The largest solver.rho_inf at which newmark's rebound is measured to converge.
RHO_INF_CONTACT = 0.5


def newmark_contact(case: Case) -> list[str]:
    """The warning of a newmark run with contact: an ``[[obstacle]]`` (fixed or a free
    body) or ``solver.self_contact``.

    Measured on the drop of benchmarks/peers/mujoco_drop.toml (a 12 kg box dropped onto
    a net, 23.8 kg m/s at impact): at rho_inf = 0.8 the box leaves with 21, 37, 29 kg m/s
    at dt = 1, 0.5, 0.25 ms and up to 2.5 kg m/s sideways in a symmetric scene; implicit
    Euler gives 15.0, 15.6, 15.8 and newmark at rho_inf = 0.5 16.0, 16.3 (0 sideways).
    A ball (three DOFs, no rotation) does the same (29, 36, 35 against 20.1, 20.1 at 0.5),
    so it is the contact, not the body's rotation. The likely mechanism: the barrier is a
    mode far beyond 1/h that the scheme's acceleration state keeps ringing (a factor
    rho_inf per step), and the one-sided barrier turns that ringing into energy. A net
    dropped onto a fixed box: newmark's steps (solved to 0.01 rtol) fail at first contact
    at any rho_inf, Newton stalling at round-off just above that tolerance; with
    solver.rtol = 1e-6 they pass (docs/howto/dynamic-runs.md). bdf2 gives 16.3 at 10 ms
    and 16.2 at 0.3 ms (benchmarks/drop.py): the warning names it."""
    solver = case.solver
    if solver.method != "dynamic" or solver.integrator != "newmark":
        return []
    if not case.obstacles and not solver.self_contact:
        return []
    head = f"solver.integrator = 'newmark' with contact (solver.rho_inf = {solver.rho_inf!r}): "
    if solver.rho_inf > RHO_INF_CONTACT:
        what = (
            "newmark gains momentum in impacts at this rho_inf and does not converge with "
            "the step (a box dropped onto a net left it faster than it came); "
            f"set solver.rho_inf <= {RHO_INF_CONTACT} or use "
        )
    else:
        what = (
            "newmark is not validated in contact (a net dropped onto a fixed box: its "
            "steps fail at first contact, their 0.01 rtol being below the barrier's "
            "round-off); if a step fails, use "
        )
    return [
        head + what + "solver.integrator = 'bdf2' (second order and right in contact) or "
        "'implicit_euler' (docs/howto/dynamic-runs.md)"
    ]


#: The integrator's own loss (a share of the run's largest energy) that earns a warning.
LOSS_WARN = 0.2


def integrator_loss(case: Case, result) -> str | None:
    """The warning of a dynamic run to a time (not to rest), with contact or undamped,
    whose integrator removed more than LOSS_WARN of the run's largest energy on its own
    (the balance's ``numerical``
    column: not damping, not friction): its motion after an impact, a rebound, peak
    forces, depend on the step. Measured on the drop of benchmarks/peers/mujoco_drop.toml
    (benchmarks/drop.py): implicit Euler at the default 10 ms loses 49 % and the box
    leaves with 47 % too little momentum; at 2.5 ms 22 % and 15 %; bdf2 at 10 ms loses
    10.5 % (the net's ringing, which it cannot resolve) with the box within 1 %."""
    solver = case.solver
    energy, scale = result.energy, result.energy_scale
    if solver.method != "dynamic" or solver.t_end == "rest" or energy is None:
        return None
    if not (case.obstacles or solver.self_contact) and solver.damping > 0:
        return None  # the paper's damped runs: implicit Euler's loss is part of the method
    if not scale > 0.0:
        return None
    lost = -float(energy[-1]) / scale
    if not lost > LOSS_WARN:
        return None
    name = solver.integrator
    if solver.tolerance is not None:
        steps = f"steps chosen by solver.tolerance = {solver.tolerance:g}"
        remedy = "a smaller solver.tolerance"
    else:
        steps = f"solver.dt = {solver.dt:g} s"
        remedy = "a smaller solver.dt"
    if name == "implicit_euler":
        remedy = (
            "solver.integrator = 'bdf2' (second order: it keeps what implicit Euler damps), "
            + remedy
            + ", or steps chosen by accuracy (solver.tolerance)"
        )
    return (
        f"the integrator ({name}, {steps}) removed {lost:.0%} of the run's largest energy on "
        "its own (the energy balance's 'numerical' part; not damping or friction): the "
        "motion, a rebound after an impact and the peak forces depend on the step here; "
        f"check with {remedy} (docs/howto/dynamic-runs.md)"
    )
