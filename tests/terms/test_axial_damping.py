"""Internal axial damping (``catenet.terms.axial``, ``material.axial_damping``): its
exact derivatives, the closed form of a damped axial oscillator (the logarithmic
decrement of a mass on a cable with a dashpot in parallel), the energy balance booking
its losses, a static equilibrium it does not change, and the key in a case."""

from __future__ import annotations

import math

import numpy as np
import pytest

from catenet.case import build, parse_case
from catenet.model.builders import Material, cable
from catenet.model.histories import Sine
from catenet.model.net import Loads, Net
from catenet.scene import Scene
from catenet.solver.path import Start, solve
from catenet.terms import check_derivatives
from catenet.terms.axial import AxialDamping


def test_derivatives_against_finite_differences():
    rng = np.random.default_rng(3)
    nodes = rng.standard_normal((6, 3))
    net = Net.from_arrays(
        nodes, [[0, 1], [1, 2], [2, 3], [3, 4], [4, 5], [1, 4]], EA=1e5, fixed=[0]
    )
    term = AxialDamping(net, rng.uniform(0.5, 2.0, net.n_edges))
    term.begin_step(nodes, 0.2, 0.1)
    term.set_motion(50.0, nodes + 0.1 * rng.standard_normal(nodes.shape), 0.0, nodes)
    grad_err, hess_err = check_derivatives(term, nodes + 0.01 * rng.standard_normal(nodes.shape))
    assert grad_err < 1e-7 and hess_err < 1e-7


EA, L0, MASS = 1e6, 1.0, 10.0  # the damped bar's (``bar``)
OMEGA = math.sqrt(EA / L0 / MASS)


def bar(zeta: float, loads: Loads) -> Scene:
    """A mass MASS on a bilateral bar (k = EA / l0) fixed at x = 0, with a dashpot c / l0 =
    2 zeta sqrt(k m) (its damping ratio zeta), under ``loads``."""
    c = 2.0 * zeta * math.sqrt(EA / L0 * MASS) * L0
    net = cable([0, 0, 0], [L0, 0, 0], 2, Material(EA=EA, line_density=2 * MASS / L0))
    net = net.replace(fixed=np.array([True, False]), tension_only=np.array([False]))
    return Scene.of(net, loads).with_terms(AxialDamping(net, np.array([c])))


def oscillator(zeta: float, integrator: str = "bdf2", periods: float = 6.0, per: int = 400):
    """The damped bar's mass (``bar``) pulled 1 mm along the bar and let go: its
    displacement over time."""
    l0 = L0
    scene = bar(zeta, Loads())
    x0 = scene.net.nodes.copy()
    x0[1, 0] += 1e-3
    period = 2 * math.pi / OMEGA
    r, steps = run(scene, integrator, period / per, periods * period, Start(x=x0))
    return r, [(t, x[1, 0] - l0, e) for t, x, e in steps], period


def run(scene: Scene, integrator: str, dt: float, t_end: float, start: Start | None = None):
    """The undamped (solver.damping = 0) run of a scene at fixed steps: its result and each
    step's (time, x, energy balance)."""
    rows = []
    r = solve(
        scene,
        method="dynamic",
        dt=dt,
        t_end=t_end,
        damping=0.0,
        integrator=integrator,
        start=start,
        on_step=lambda s: rows.append((s.time, s.x.copy(), s.energy.copy())) and False,
    )
    return r, rows


def test_a_damped_oscillator_decays_at_its_logarithmic_decrement():
    """Successive maxima of the displacement fall by exp(-2 pi zeta / sqrt(1 - zeta^2))
    (bdf2 at 400 steps a period: its own damping is below 1e-5 of critical)."""
    zeta = 0.05
    _, rows, _ = oscillator(zeta)
    t, u = np.array([(a, b) for a, b, _ in rows]).T
    top = np.flatnonzero((u[1:-1] > u[:-2]) & (u[1:-1] >= u[2:])) + 1
    peaks = u[top]
    assert len(peaks) >= 5
    decrement = float(np.mean(np.log(peaks[:-1] / peaks[1:])))
    assert decrement == pytest.approx(2 * math.pi * zeta / math.sqrt(1 - zeta**2), rel=5e-3)


def shaken(integrator: str, per: int, zeta: float = 0.5, periods: float = 8.0):
    """The oscillator's support shaken along the bar, x_s = A sin(Omega t) (Omega half the
    bar's omega): the mass's largest displacement from the support over the last two
    periods, and the closed form of the steady state, A Omega^2 / sqrt((omega^2 -
    Omega^2)^2 + (2 zeta omega Omega)^2)."""
    amplitude, omega, l0 = 1e-3, OMEGA, L0
    shake = np.zeros((2, 3))
    shake[0, 0] = amplitude
    period = 2.0 * math.pi / (0.5 * omega)
    loads = Loads(support_displacement=shake, support_history=[(np.array([0]), Sine(period))])
    r, steps = run(bar(zeta, loads), integrator, period / per, periods * period)
    t, u = np.array([(t, x[1, 0] - x[0, 0] - l0) for t, x, _ in steps]).T
    late = t > (periods - 2.0) * period
    ratio = 0.5 * omega
    closed = amplitude * ratio**2 / math.hypot(omega**2 - ratio**2, 2 * zeta * omega * ratio)
    return r, float(np.max(np.abs(u[late]))), closed


def test_a_shaken_support_drives_the_dashpot_at_the_schemes_own_velocity():
    """A support's velocity in a step is the scheme's own formula on its path
    (``Scheme.held``), as its free node's is: the steady response of the mass on a damped
    bar whose support is shaken, undamped otherwise, against its closed form: bdf2 1.6 %
    off at 40 steps a period and second order (0.36 % at 80); implicit Euler first order
    (6 %, 0.8 % at 320), and so is newmark's, its support's mean velocity over the step
    (16 %, 8 % at 80). Before, bdf2 gave a support (x_end - x_n) / b, 1.5 times its
    velocity, and the response came out 58 % off at 40 steps and 43 % at 320. The
    support starts at once (no ramp): its reaction through the dashpot is booked at the
    step's end, as the dashpot's losses are, and the balance closes (the trapezoid of that
    reaction missed half the first step's pull and the run stopped, "the integrator
    creates energy")."""
    errors = []
    for per in (40, 80):
        r, peak, closed = shaken("bdf2", per)
        assert r.converged
        assert not np.any(r.contact_force)  # the ropes' own force: no contact
        errors.append(abs(peak / closed - 1.0))
    assert errors[0] < 0.02 and errors[1] < 0.3 * errors[0], errors
    first = []
    for per in (40, 320):
        r, peak, closed = shaken("implicit_euler", per)
        assert r.converged and r.energy[-1] < 1e-3 * r.energy_scale  # a loss: its own
        first.append(abs(peak / closed - 1.0))
    assert first[0] < 0.1 and first[1] < 0.2 * first[0], first
    mean = [abs(shaken("newmark", per)[1] / closed - 1.0) for per in (40, 80)]
    assert mean[0] < 0.2 and 0.4 < mean[1] / mean[0] < 0.6, mean  # first order: halved


def test_its_losses_close_the_energy_balance():
    """The energy the oscillator loses is what the dashpot dissipated: the balance's
    remainder is a loss (implicit Euler's own) or a small share of the start's energy
    (bdf2)."""
    for integrator in ("bdf2", "implicit_euler"):
        _, rows, _ = oscillator(0.05, integrator, periods=3.0, per=200)
        k, u, c, work, lost, left = rows[-1][2]
        start = 0.5 * 1e6 * 1e-6  # 1/2 k u0^2
        assert lost > 0.5 * start and work == 0.0
        assert left < 1e-3 * start, (integrator, rows[-1][2])
        if integrator == "bdf2":  # its own loss: (omega h)^3 / 4 of critical, and the
            assert abs(left) < 3e-3 * start  # mean rule's error on the dashpot's work


def test_a_static_equilibrium_is_the_same_with_it():
    """A static step sees no damping (nothing moves): a hanging cable's equilibrium is the
    same, bit for bit."""
    net = cable([0, 0, 0], [10, 0, 0], 11, Material(EA=1e6, line_density=1.0), length=10.5)
    loads = Loads(gravity=np.array([0.0, 0.0, -9.81]))
    plain = solve(Scene.of(net, loads))
    damped = solve(Scene.of(net, loads).with_terms(AxialDamping(net, np.full(10, 1e3))))
    assert np.array_equal(plain.x, damped.x)


CASE = {
    "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [10, 0, 0], "nodes": 11},
    "material": {"EA": 1e6, "density": 7850.0, "area": 1e-4, "axial_damping": 2e3},
    "load": {"gravity": [0.0, 0.0, -9.81]},
    "solver": {"method": "dynamic", "dt": 0.01, "t_end": 0.1},
}


def test_the_key_puts_the_dashpots_on_its_edges_and_bad_values_exit_2(tmp_path):
    from click.testing import CliRunner

    from catenet.case import dumps_toml
    from catenet.cli import main

    scene = build(parse_case(CASE))
    (term,) = [t for t in scene.terms if isinstance(t, AxialDamping)]
    assert np.allclose(term.rate * scene.net.rest_length, 2e3)
    static = {**CASE, "solver": {"method": "static"}}
    assert not any(isinstance(t, AxialDamping) for t in build(parse_case(static)).terms)
    for bad in (-1.0, "a lot"):
        case = {**CASE, "material": {**CASE["material"], "axial_damping": bad}}
        path = tmp_path / "bad.toml"
        path.write_text(dumps_toml(case))
        r = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "o.h5")])
        assert r.exit_code == 2 and "material.axial_damping" in r.output, r.output
        assert "Traceback" not in r.output
