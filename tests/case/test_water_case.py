"""Cases in water (docs/howto/mooring-dynamics.md): a taut line in a current deflects as
the string under the drag's line load, a sine support motion exact and ramped, a
dynamic run from its own static equilibrium, the mooring chain of configs/water whose
peak fairlead tension converges with the time step, the Airy and JONSWAP kinematics, and
bad input's messages (exit 2)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from catenet.case import load_case, parse_case
from catenet.case.scene import build
from catenet.cli import main
from catenet.model.water import Water, Wave, jonswap, wave_number
from catenet.solver.path import Settings, solve

ROOT = Path(__file__).resolve().parents[2]
MOORING = ROOT / "configs" / "water" / "mooring_surge.toml"


def line_case(**over) -> dict:
    """A vertical line 40 m long, 10 m below the surface, pinned at both ends at
    tension T = 50 kN, in a uniform current of 1 m/s along x."""
    case = {
        "geometry": {"kind": "cable", "start": [0, 0, -50.0], "end": [0, 0, -10.0], "nodes": 41},
        "material": {"EA": 1e7, "prestress": 5e4, "hydro_diameter": 0.1, "cd_n": 1.2},
        "water": {"current": [[-100.0, 1.0, 0.0], [0.0, 1.0, 0.0]]},
        "solver": {"method": "static"},
    }
    for k, v in over.items():
        case[k] = {**case.get(k, {}), **v}
    return case


def run(case: dict, **keys):
    c = parse_case(case)
    scene = build(c)
    return c, scene, solve(scene, Settings.of(c.solver), **keys)


def test_a_taut_line_in_a_current_deflects_as_a_string_under_its_drag():
    """The static drag of the current on the line at rest, q = 1/2 rho_w cd_n d U^2 per
    length normal to it, bends the taut line into the string's parabola, q L^2 / (8 T)
    at the middle, T the string's tension (the prestress and the deflection's stretch),
    to O(slope^2) (the drag is that of the velocity normal to the deflected line),
    whatever the load steps; no current, no deflection."""
    c, scene, r = run(line_case())
    q = 0.5 * 1025.0 * 1.2 * 0.1 * 1.0**2
    e = np.diff(r.x, axis=0)
    along = r.tension * e[:, 2] / np.linalg.norm(e, axis=1)  # the string's tension
    assert np.ptp(along) < 1e-3 * along.mean()  # constant to O(slope^2)
    assert 5e4 < along.mean() < 5.1e4  # the prestress and the stretch of the deflection
    expected = q * 40.0**2 / (8 * along.mean())
    mid = scene.net.n_nodes // 2
    assert r.x[mid, 0] == pytest.approx(expected, rel=2e-3)
    assert np.allclose(r.x[:, 1], 0.0, atol=1e-12)
    s = (r.x[:, 2] + 50.0) / 40.0
    assert np.allclose(r.x[:, 0], 4 * expected * s * (1 - s), rtol=3e-3, atol=1e-4)
    _, _, r4 = run(line_case(solver={"steps": 4}))
    assert np.allclose(r4.x, r.x, atol=1e-6 * expected)
    _, _, still = run(line_case(water={"current": [[0.0, 0.0, 0.0]]}))
    assert np.abs(still.x[:, 0]).max() < 1e-12


def test_the_supports_carry_the_whole_currents_drag():
    """The reactions of the taut line in its current sum to minus the drag on the whole
    line, q L (the half edges at the supports' nodes included, as their weight is), to
    O(slope^2), in the static answer and in a dynamic run from it at rest. They summed
    2.5 % short (1/40 at 40 edges) while the supports' half edges had no drag."""
    q = 0.5 * 1025.0 * 1.2 * 0.1 * 1.0**2
    _, _, r = run(line_case())
    total = r.reaction.sum(axis=0)
    assert total[0] == pytest.approx(-q * 40.0, rel=1e-3)
    assert abs(total[1]) < 1e-9 * q * 40.0
    dyn = line_case(
        material={"area": 0.005, "density": 1025.0},  # neutral: the same static answer
        solver={"method": "dynamic", "dt": 0.05, "t_end": 0.2},
    )
    dyn["solver"]["initial_state"] = "equilibrium"
    _, _, moving = run(dyn)
    assert moving.reaction.sum(axis=0)[0] == pytest.approx(total[0], rel=1e-6)


@pytest.mark.parametrize("ramp", [None, 0.0, 0.25])
def test_sine_motion_of_a_support(ramp):
    """supports.move sine: the support at A r(t) sin(2 pi t / T + phase) at every step,
    r the smooth start (1 - cos(pi t / ramp)) / 2 over ramp (default: one period; 0:
    none); a static run takes it at t = 0."""
    sine = {"amplitude": [0.1, 0.0, 0.05], "period": 0.5, "phase": 30.0}
    if ramp is not None:
        sine["ramp"] = ramp
    case = line_case(
        supports={"move": [{"node": "end", "sine": sine}]},
        solver={"method": "dynamic", "dt": 0.01, "t_end": 0.7, "damping": 1.0},
        material={"area": 1e-3, "density": 7850.0},
    )
    seen = []
    c, scene, r = run(case, on_step=lambda st: seen.append((st.time, st.x[-1].copy())) and False)
    ramp_t = 0.5 if ramp is None else ramp
    for t, x in seen:
        r_t = 1.0 if ramp_t == 0 or t >= ramp_t else 0.5 * (1 - math.cos(math.pi * t / ramp_t))
        factor = r_t * math.sin(2 * math.pi * t / 0.5 + math.radians(30.0))
        expected = np.array([0.0, 0.0, -10.0]) + factor * np.array([0.1, 0.0, 0.05])
        assert np.allclose(x, expected, atol=1e-12)
    assert len(seen) == 70
    static = dict(case, solver={"method": "static"})
    _, sc, rs = run(static)
    at0 = 0.0 if ramp_t > 0 else math.sin(math.radians(30.0))  # the sine at t = 0
    assert np.allclose(rs.x[-1], at0 * np.array([0.1, 0.0, 0.05]) + [0, 0, -10.0], atol=1e-12)


def chain_case(**solver) -> dict:
    """A chain hanging in water between two supports, in a current: weight, buoyancy
    and drag at rest."""
    return {
        "geometry": {
            "kind": "cable",
            "start": [0, 0, -40.0],
            "end": [30, 0, -5.0],
            "nodes": 21,
            "length": 50.0,
        },
        "material": {"EA": 1e8, "area": 0.005, "density": 7850.0, "cd_n": 2.0},
        "water": {"current": [[-50.0, 0.3, 0.2], [0.0, 0.8, 0.0]]},
        "load": {"gravity": [0, 0, -9.81]},
        "solver": {"method": "static", **solver},
    }


def test_a_run_from_its_equilibrium_starts_and_stays_at_rest():
    """solver.initial_state = "equilibrium": the dynamic run starts from the static
    solution (weight, buoyancy, current), at rest (no kinetic energy at t = 0), and
    nothing moves while nothing changes; the peaks count from t = 0."""
    case = chain_case()
    _, _, static = run(case)
    dyn = dict(case, solver={"method": "dynamic", "dt": 0.05, "t_end": 1.0})
    dyn["solver"]["initial_state"] = "equilibrium"
    rows, xs = [], []

    def seen(st):
        rows.append(st.energy)
        xs.append(st.x.copy())

    c, scene, r = run(dyn, on_step=seen)
    assert c.solver.damping == 0.0  # the water damps
    scale = np.abs(static.x).max()
    assert np.abs(xs[0] - static.x).max() < 1e-7 * scale
    assert np.abs(r.x - static.x).max() < 1e-7 * scale
    assert np.abs(r.v).max() < 1e-6
    assert rows[0][0] < 1e-9 * max(abs(rows[0][2]), 1.0)  # kinetic
    assert np.allclose(r.peaks.tension, static.tension, rtol=1e-6)


def test_the_mooring_chains_peak_tension_converges_with_the_step():
    """configs/water/mooring_surge.toml (800 m of studless chain in 100 m of water,
    the fairlead surged +-5 m at 12 s, from its equilibrium): the peak fairlead tension
    changes by < 1 % between dt and dt / 2, since drag, not the integrator, damps the
    line (coarser edges and one and a quarter periods here, to keep it short)."""
    peaks, rows = [], []
    for dt in (0.1, 0.05):
        c = load_case(MOORING, [f"solver.dt={dt}", "solver.t_end=15", "geometry.edge_length=20"])
        r = solve(build(c), Settings.of(c.solver), on_step=lambda st: rows.append(st.energy))
        peaks.append(float(np.max(r.peaks.tension)))
    assert 2.3e5 < peaks[1] < 3.2e5
    assert abs(peaks[0] - peaks[1]) < 0.01 * peaks[1]
    # the balance closes: the work put in leaves through the drag (implicit Euler's
    # own loss is the small negative remainder)
    kinetic, elastic, contact, work, lost, left = rows[-1]
    assert lost > 0.5 * work > 0
    assert -0.03 * work < left <= 0.0


def test_airy_kinematics():
    """Linear wave kinematics: the dispersion relation, the surface's vertical velocity
    d eta / dt, continuity (du/dx + dw/dz = 0), finite depth tending to deep water, the
    ramp's smooth start; a JONSWAP sea's components make its significant height."""
    g, depth, omega = 9.81, 30.0, 0.8
    k = wave_number(omega, g, depth)
    assert omega**2 == pytest.approx(g * k * math.tanh(k * depth), rel=1e-13)
    water = Water(1025.0, g=g, waves=(Wave(1.5, omega, 0.0, 0.4),), depth=depth)
    t = 3.1
    x = np.array([[2.0, 0.0, 0.0], [2.0, 0.0, -7.0], [2.0, 0.0, -30.0]])
    v, a = water.flow(x, t)
    theta = k * 2.0 - omega * t + 0.4
    assert v[0, 2] == pytest.approx(1.5 * omega * math.sin(theta), rel=1e-12)  # d eta / dt
    assert abs(v[2, 2]) < 1e-12  # no flow through the seabed
    h = 1e-5
    p = np.array([[2.0, 0.0, -7.0]])
    dudx = (water.flow(p + [h, 0, 0], t)[0] - water.flow(p - [h, 0, 0], t)[0])[0, 0] / (2 * h)
    dwdz = (water.flow(p + [0, 0, h], t)[0] - water.flow(p - [0, 0, h], t)[0])[0, 2] / (2 * h)
    assert abs(dudx + dwdz) < 1e-8 * abs(dudx)
    dvdt = (water.flow(x, t + h)[0] - water.flow(x, t - h)[0]) / (2 * h)
    assert np.allclose(a, dvdt, rtol=1e-7, atol=1e-9)
    deep = Water(1025.0, g=g, waves=(Wave(1.5, 2.0),))
    nearly = Water(1025.0, g=g, waves=(Wave(1.5, 2.0),), depth=1000.0)
    assert np.allclose(deep.flow(x, t)[0], nearly.flow(x, t)[0], rtol=1e-10, atol=1e-12)
    ramped = Water(1025.0, g=g, waves=(Wave(1.5, omega),), ramp=10.0)
    assert np.abs(ramped.flow(x, 0.0)[0]).max() == 0.0
    sea = jonswap(4.0, 10.0, 3.3, seed=7)
    assert 4.0 * math.sqrt(sum(w.amplitude**2 / 2 for w in sea)) == pytest.approx(4.0, rel=1e-12)
    assert jonswap(4.0, 10.0, 3.3, seed=7) == sea


@pytest.mark.parametrize("depth", [None, 30.0])
def test_a_sea_is_the_sum_of_its_components(monkeypatch, depth):
    """A JONSWAP sea (100 components, turned 0.3 rad) and a regular wave across it, at
    points above the surface, in the water and at the seabed: its velocity and
    acceleration are those of each component alone, summed (the components are
    evaluated together, a block of points at a time: the same with blocks of 7)."""
    import catenet.model.water as water_model

    waves = (*jonswap(6.0, 10.0, 3.3, seed=7, direction=0.3), Wave(1.0, 0.7, 1.0, 0.2))
    sea = Water(1025.0, g=9.81, waves=waves, depth=depth, ramp=10.0)
    x = np.random.default_rng(1).uniform(-300.0, 300.0, (45, 3))
    x[:, 2] = np.linspace(-30.0, 2.0, 45)
    for t in (3.0, 25.0):
        parts = [Water(1025.0, g=9.81, waves=(w,), depth=depth, ramp=10.0) for w in waves]
        v = sum(p.flow(x, t)[0] for p in parts)
        a = sum(p.flow(x, t)[1] for p in parts)
        for chunk in (water_model.CHUNK, 7):
            monkeypatch.setattr(water_model, "CHUNK", chunk)
            vel, acc = sea.flow(x, t)
            assert np.abs(vel - v).max() < 1e-13 * np.abs(v).max()
            assert np.abs(acc - a).max() < 1e-13 * np.abs(a).max()


BASE = """
[geometry]
kind = "cable"
start = [0, 0, -50.0]
end = [0, 0, -10.0]
nodes = 5
[material]
{material}
[water]
{water}
[load]
{load}
[solver]
{solver}
[[supports.move]]
node = "end"
{move}
"""


@pytest.mark.parametrize(
    "parts, message",
    [
        ({"water": "current = [[0, 1]]"}, "water.current[0]"),
        ({"water": "current = [[0, 1, 0], [0, 2, 0]]"}, "two rows at one depth"),
        ({"water": 'spectrum = "jonswap"\nhs = 2.0'}, "water.tp: missing"),
        ({"water": "hs = 2.0"}, "only with water.spectrum"),
        ({"water": "[[water.wave]]\nheight = 1.0\nperiod = 0"}, "water.wave[0].period"),
        ({"water": "density = -1"}, "water.density"),
        ({"water": "current = [[0, 1e100, 0]]"}, "a speed beyond"),
        ({"water": 'spectrum = "jonswap"\nhs = 1e100\ntp = 1.0'}, "water.hs: height"),
        (
            {"water": 'depth = 1e-300\nspectrum = "jonswap"\nhs = 2.0\ntp = 8.0'},
            "water.hs: height 2 m in water.depth = 1e-300 m: a wave higher than 0.78",
        ),
        ({"water": 'spectrum = "jonswap"\nhs = 1.0\ntp = 1.0\ngamma = 1e100'}, "water.gamma"),
        (
            {"material": "EA = 1e6", "load": "", "solver": 'method = "static"'},
            "material.hydro_diameter: missing",
        ),
        ({"material": "EA = 1e6\nhydro_diameter = 0.1\ncd_n = -1"}, "material.cd_n"),
        ({"load": "gravity = [1.0, 0, -9.81]"}, "must point along -z"),
        (
            {"move": "sine = { amplitude = [1, 0, 0], period = 1 }\ndisplacement = [1, 0, 0]"},
            "not both",
        ),
        ({"move": "sine = { amplitude = [1, 0, 0] }"}, "supports.move[0].sine.period: missing"),
        ({"move": "sine = { amplitude = [1, 0, 0], period = 2, ramp = -1 }"}, "sine.ramp"),
        ({"move": "sine = { amplitude = [1, 0, 0], period = 2 }\nduration = 1.0"}, "no history"),
        ({"move": ""}, "give displacement"),
        ({"solver": 'method = "dynamic"\ninitial_state = "rest"'}, "solver.initial_state"),
    ],
)
def test_bad_water_input_exits_2(tmp_path, parts, message):
    values = {
        "material": "EA = 1e6\narea = 1e-3\ndensity = 7850.0",
        "water": "",
        "load": "gravity = [0, 0, -9.81]",
        "solver": 'method = "dynamic"\nt_end = 0.1',
        "move": "sine = { amplitude = [0.1, 0, 0], period = 1.0 }",
    }
    values.update(parts)
    text = BASE.format(**values)
    if "[[water.wave]]" in values["water"]:  # after the table's own keys
        text = text.replace("[water]\n" + values["water"], "[water]\n") + values["water"] + "\n"
    path = tmp_path / "case.toml"
    path.write_text(text)
    r = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "out.h5"), "-q"])
    assert r.exit_code == 2, r.output
    assert message in r.stderr, r.stderr
    assert "Traceback" not in r.output


def test_modes_in_water_take_the_materials_added_mass():
    """catenet modes of a case with [water]: each edge's added mass is rho_w ca_n A l0
    normal to it and rho_w ca_t A l0 along it (the materials')."""
    from catenet.run.modes import added_line

    case = line_case(material={"area": 1e-3, "density": 7850.0, "ca_n": 0.8, "ca_t": 0.3})
    c = parse_case(case)
    scene = build(c)
    line = added_line(c, scene)
    assert line is not None and line.shape == (scene.net.n_edges, 2)
    water = 1025.0 * 1e-3 * scene.net.rest_length
    assert np.allclose(line[:, 0], 0.8 * water, rtol=1e-14)
    assert np.allclose(line[:, 1], 0.3 * water, rtol=1e-14)


def test_a_wave_higher_than_its_seabeds_depth_allows_exits_2(tmp_path):
    """A 2 m wave over a seabed (a plane obstacle) 1 m below the still level breaks: the
    seabed's depth is checked as a given water.depth is (McCowan's 0.78; a depth of
    1e-300 m made the waves' speeds infinite and the run failed at t = 0)."""
    text = BASE.format(
        material="EA = 1e6\narea = 1e-3\ndensity = 7850.0",
        water='spectrum = "jonswap"\nhs = 2.0\ntp = 8.0',
        load="gravity = [0, 0, -9.81]",
        solver='method = "dynamic"\nt_end = 0.1',
        move="sine = { amplitude = [0.1, 0, 0], period = 1.0 }",
    ).replace("end = [0, 0, -10.0]", "end = [2.0, 0, -0.5]")
    text = text.replace("start = [0, 0, -50.0]", "start = [-2.0, 0, -0.5]")
    text += '[[obstacle]]\nkind = "plane"\npoint = [0, 0, -1.0]\nnormal = [0, 0, 1]\n'
    path = tmp_path / "case.toml"
    path.write_text(text)
    r = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "out.h5"), "-q"])
    assert r.exit_code == 2, r.output
    assert "water.hs: height 2 m in the seabed's depth (a plane obstacle) = 1 m" in r.stderr


def test_shallow_water_kinematics_to_round_off():
    """Where k h is far below round-off's share of 1 (a depth of 1e-60 m) the profiles
    are the shallow-water limit, the surface's horizontal speed a omega / (k h) cos(theta)
    (1 - exp(-2 k h) lost its digits there)."""
    g, depth, omega, a = 9.81, 1e-60, 0.8, 1e-61
    k = wave_number(omega, g, depth)
    water = Water(1025.0, g=g, waves=(Wave(a, omega, 0.0, 0.0),), depth=depth)
    v, _ = water.flow(np.array([[0.0, 0.0, 0.0]]), 0.0)
    assert v[0, 0] == pytest.approx(a * omega / math.tanh(k * depth), rel=1e-12)


def test_a_rope_jerked_through_water_runs_at_a_tight_tolerance():
    """A slack 55 m rope in water, its end pulled 9 m from t = 1 s, from its equilibrium,
    at solver.tolerance = 3e-4: the water's added mass turns with the tangents from step
    to step, which changes the kinetic energy it carries at the same velocities. That is
    the water's work (``WaterForce.relagged``); booked as the integrator's, it was the
    same 9 mJ in every try of the step after the pull began, from 1e-4 s down to 5e-11 s,
    over an allowance of 7 mJ, and the run failed at t = 1.0272 s. It runs now, and its
    integrator's own energy stays a loss."""
    case = parse_case({
        "geometry": {"kind": "cable", "start": [0.0, 0.0, -20.0], "end": [45.0, 0.0, -2.0],
                     "length": 55.0, "nodes": 56},
        "material": {"EA": 3.0e7, "area": 0.005, "density": 1380.0},
        "water": {},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "supports": {"move": [{"node": "end", "displacement": [9.0, 0.0, 0.0],
                               "history": [[0.0, 0.0], [1.0, 0.0], [3.0, 1.0]]}]},
        "solver": {"method": "dynamic", "initial_state": "equilibrium", "t_end": 1.5,
                   "tolerance": 3e-4},
    })  # fmt: skip
    rows, times = [], []

    def seen(st) -> bool:  # the first 40 ms of the pull (the whole run: 30 s)
        rows.append(st.energy)
        times.append(st.time)
        return st.time > 1.04

    solve(build(case), Settings.of(case.solver), on_step=seen)
    assert times[-1] > 1.04
    kinetic, elastic, contact, work, lost, left = rows[-1]
    assert kinetic > 1.0 and -1e-2 * max(abs(contact), work) < left <= 0.0


def _wire(units: str, **water) -> dict:
    """A 76 mm wire catenary in 120 m of water (the fairlead 5 m down), in ``units``
    (SI, kN-m or N-mm): the same line in each."""
    length, force, mass = {"SI": (1.0, 1.0, 1.0), "kN-m": (1.0, 1e-3, 1e-3),
                           "N-mm": (1e3, 1.0, 1e-3)}[units]  # fmt: skip
    case = line_case()
    case["units"] = units
    case["geometry"] = {"kind": "cable", "start": [0.0, 0.0, -120.0 * length],
                        "end": [400.0 * length, 0.0, -5.0 * length], "length": 450.0 * length,
                        "nodes": 31}  # fmt: skip
    case["material"] = {"EA": 5.6e8 * force, "area": 3.5e-3 * length**2,
                        "density": 7850.0 * mass / length**3,
                        "hydro_diameter": 0.076 * length}  # fmt: skip
    case["load"] = {"gravity": [0.0, 0.0, -9.81 * length]}
    case["water"] = dict(water)
    return case


@pytest.mark.parametrize("units", ["kN-m", "N-mm"])
def test_the_waters_density_left_out_is_sea_waters_in_the_cases_units(units):
    """water.density (and material.water_density, modes' added mass) left out is 1025
    kg/m^3 in the case's units: 1.025 t/m^3 in kN-m, 1.025e-9 t/mm^3 in N-mm. In kN-m it
    was 1025 t/m^3: a wire catenary 1000 times buoyant came out at 22 MN, silently.
    Given as 1025 there, a unit slip is warned, as a material's density is."""
    from catenet.run.advice import unit_slips

    _, _, si = run(_wire("SI"))
    c, _, r = run(_wire(units))
    scale = {"kN-m": 1e3, "N-mm": 1.0}[units]  # N per the case's force unit
    assert float(r.tension.max()) * scale == pytest.approx(float(si.tension.max()), rel=1e-6)
    assert c.water.density == pytest.approx(1025.0 / {"kN-m": 1e3, "N-mm": 1e12}[units])
    assert c.material.water_density == c.water.density
    slipped = parse_case(_wire(units, density=1025.0))
    said = unit_slips(slipped, build(slipped).net)
    assert any("check units: water.density = 1025" in s for s in said), said


def test_a_line_in_water_relaxes_to_its_equilibrium():
    """solver.t_end = "rest" in water: a run to rest keeps the default damping (water
    alone sets it to 0 for a run whose motion is the answer), so it comes to rest at the
    static equilibrium. It failed with "solver.damping = 0: an undamped run never rests",
    a damping the case never gave."""
    static = _wire("SI")
    _, _, s = run(static)
    relaxed = dict(static, solver={"method": "dynamic", "t_end": "rest"})
    c, _, r = run(relaxed)
    assert c.solver.damping > 0.0 and r.converged
    assert np.abs(r.x - s.x).max() < 1e-4 * np.abs(s.x).max()


def test_implicit_euler_is_judged_by_its_own_rule_for_a_moving_supports_work():
    """A chain on the seabed surged 4 m at 12 s by its fairlead, implicit Euler at 1 s
    steps: the supports' work booked by the trapezoid, 1/2 (R_n + R_n+1) . dx, differs
    from implicit Euler's own energy identity (R_n+1 . dx) by 1/2 (R_n+1 - R_n) . dx,
    about 1e5 J where the fairlead moves 2 m while its pull rises by 100 kN, and the run
    stopped: "the integrator creates energy". Judged by its own rule (the remainder
    reported still the trapezoid's), the run ends, its remainder a loss."""
    case = {
        "geometry": {"kind": "graph", "nodes": [[0.0, 0.0, -100.0], [470.0, 0.0, -5.0]],
                     "fixed": [0, 1], "edge_length": 9.59, "prestrain": -0.040975,
                     "sets": {"fairlead": [1]}, "cable": [{"name": "chain", "nodes": [0, 1]}]},
        "material": {"EA": 4.9e8, "area": 0.01465, "density": 7850.0, "hydro_diameter": 0.137,
                     "cd_n": 2.4, "cd_t": 1.15, "ca_n": 1.0, "ca_t": 0.5},
        "water": {},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "obstacle": [{"kind": "plane", "point": [0.0, 0.0, -100.0], "normal": [0.0, 0.0, 1.0]}],
        "supports": {"move": [{"node": "fairlead",
                               "sine": {"amplitude": [4.0, 0.0, 0.0], "period": 12.0}}]},
        "solver": {"method": "dynamic", "initial_state": "equilibrium", "t_end": 16.0,
                   "dt": 1.0},
    }  # fmt: skip
    rows = []
    c, _, r = run(case, on_step=lambda st: rows.append(st.energy))
    assert c.solver.integrator == "implicit_euler" and r.converged and r.time == 16.0
    assert rows[-1][-1] < 0.0


def test_steps_chosen_by_accuracy_follow_a_wave():
    """A chain in 60 m of water under a 10 m, 12 s wave and a current, from its
    equilibrium: the error estimate sees the chain's response, not the wave that drives
    it, and the default steps grew to 4.6-7 s (23 steps over four periods), the peak
    tension 3.2 % low. A wave's period now bounds the steps as a support's sine does (64
    steps a period at the default tolerance): within 0.1 % of fixed 0.05 s bdf2 steps."""
    case = {
        "geometry": {"kind": "graph", "nodes": [[-312.0, 0.0, -60.0], [0.0, 0.0, 3.0]],
                     "fixed": [0, 1], "edge_length": 7.9574, "prestrain": -0.0354635,
                     "cable": [{"name": "chain", "nodes": [0, 1]}]},
        "material": {"EA": 6.0e8, "area": 0.01783, "density": 7850.0, "hydro_diameter": 0.151,
                     "cd_n": 2.4, "cd_t": 1.15, "ca_n": 1.0, "ca_t": 0.5},
        "water": {"current": [[-60.0, -0.5, 0.0], [0.0, -0.5, 0.0]],
                  "wave": [{"height": 10.0, "period": 12.0}]},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "obstacle": [{"kind": "plane", "point": [0.0, 0.0, -60.0], "normal": [0.0, 0.0, 1.0]}],
        "solver": {"method": "dynamic", "initial_state": "equilibrium", "t_end": 48.0},
    }  # fmt: skip
    steps = []
    _, _, default = run(case, on_step=lambda st: steps.append(st.time))
    fixed = dict(case, solver={**case["solver"], "dt": 0.05, "integrator": "bdf2"})
    _, _, fine = run(fixed)
    assert len(steps) >= 4 * 64
    peak = float(default.peaks.tension.max())
    assert peak == pytest.approx(float(fine.peaks.tension.max()), rel=1e-3)


def test_a_transient_in_water_is_not_called_undamped(tmp_path):
    """A line let go in water (solver.damping 0, as [water] sets it) stopped at its
    t_end before rest: the summary called it "undamped, it never rests"; the water's drag
    damps it, and the summary says so."""
    from catenet.case.toml import dumps_toml

    case = _wire("SI")
    case["solver"] = {"method": "dynamic", "t_end": 0.5}
    path = tmp_path / "line.toml"
    path.write_text(dumps_toml(case))
    r = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "line.h5")])
    assert r.exit_code == 0, r.output
    assert "damped only by the water's drag" in r.output
    assert "undamped" not in r.output
