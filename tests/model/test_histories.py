"""Time histories of loads and support motion, point masses and initial velocities."""

from __future__ import annotations

import copy
import logging
import subprocess

import numpy as np
import pytest

from catenet.case.parse import parse_case
from catenet.case.scene import build
from catenet.errors import ConfigError
from catenet.model.histories import History
from catenet.run import advice
from catenet.solver.path import Settings, Start, solve, workspace
from tests.conftest import catenet_command, subprocess_env

F = 10.0  # N, the point load at the cable's midpoint


def cable(method="dynamic", t_end=1.0, damping=5.0, **load) -> dict:
    """A pretensioned cable (11 nodes, strain about 1 %) with a point load at its middle."""
    point = {"node": "midpoint", "force": [0.0, 0.0, -F], **load}
    return {
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [1, 0, 0], "nodes": 11,
                     "length": 0.99},
        "material": {"E": 10e6, "radius": 0.01, "density": 1000.0},
        "load": {"point": [point]},
        "solver": {"method": method, "dt": 0.01, "damping": damping, "t_end": t_end,
                   "rtol": 1e-10},
    }  # fmt: skip


def run(data: dict, start: Start | None = None):
    """The result and the states (t, x, v) of every step."""
    scene = build(parse_case(data))
    settings = Settings.of(scene.case.solver)
    states = []

    def seen(step):
        states.append((step.time, step.x.copy(), None if step.v is None else step.v.copy()))

    result = solve(scene, settings, start=start, on_step=seen)
    return scene, result, states


# --------------------------------------------------------------------------- histories


def test_history_is_linear_between_points_and_constant_outside():
    h = History([[0.5, 0.0], [1.5, 2.0], [2.0, 1.0]])
    assert h(0.0) == 0.0 and h(0.5) == 0.0 and h(1.0) == 1.0 and h(1.75) == 1.5
    assert h(2.0) == 1.0 and h(100.0) == 1.0 and h.end == 2.0
    assert History([[0.0, 0.3]])(5.0) == 0.3  # one point: a constant factor


def test_a_step_in_the_load_history_shifts_the_response_in_time():
    """Nothing moves before the step at t = 0.5; after it, the motion is that of the same
    load applied at t = 0, shifted by 0.5 s."""
    step = [[0.0, 0.0], [0.5, 0.0], [0.505, 1.0]]
    scene, _, late = run(cable(history=step, t_end=1.0))
    _, _, early = run(cable(t_end=0.5))
    x_ref = scene.net.nodes
    before = [(t, x) for t, x, _ in late if t <= 0.5 + 1e-9]
    after = [(t, x) for t, x, _ in late if t > 0.5 + 1e-9]
    assert len(before) == 50 and len(after) == 50
    assert all(np.array_equal(x, x_ref) for _, x in before)
    mid = scene.probe
    assert after[0][1][mid, 2] < -1e-4  # it moves as soon as the load is on
    for (t_late, x_late), (t_early, x_early, _) in zip(after, early, strict=True):
        assert t_late == pytest.approx(t_early + 0.5, abs=1e-9)
        assert np.allclose(x_late, x_early, rtol=0, atol=1e-9)


def test_a_slow_ramp_gives_the_quasi_static_answer():
    """A load ramped over 20 periods is near equilibrium all along; at the end of the ramp
    the midpoint is at the static deflection, where the sudden load overshoots it."""
    _, static, _ = run(cable(method="static"))
    delta = static.x[5, 2]
    ramp = [[0.0, 0.0], [3.0, 1.0]]
    _, result, states = run(cable(history=ramp, t_end=6.0))
    at_end = next(x for t, x, _ in states if t >= 3.0 - 1e-9)
    assert at_end[5, 2] == pytest.approx(delta, rel=0.02)
    half = next(x for t, x, _ in states if t >= 1.5 - 1e-9)
    _, half_static, _ = run(cable(method="static", force=[0.0, 0.0, -F / 2]))
    assert half[5, 2] == pytest.approx(half_static.x[5, 2], rel=0.03)
    assert result.equilibrium and np.allclose(result.x, static.x, atol=1e-7)
    # The same load at once overshoots the static deflection by far more (over 15 %).
    _, _, sudden = run(cable(t_end=0.5))
    assert min(x[5, 2] for _, x, _ in sudden) < 1.15 * delta


def test_reaction_of_a_dynamic_result_uses_the_load_at_its_time():
    """A run that ends while gravity is still off: no support carries any weight (with
    gravity in full, each end would carry the weight of its half edge)."""
    data = cable(t_end=0.2)
    data["load"] = {"gravity": [0.0, 0.0, -9.81], "history": [[0.0, 0.0], [5.0, 0.0], [5.1, 1.0]]}
    scene, result, _ = run(data)
    assert scene.net.mass[0] > 0
    assert np.allclose(result.reaction[:, 2], 0.0, atol=1e-9)


def test_a_support_moved_by_a_history():
    """The end support follows factor(t) times its displacement; where the history ends
    at 0.5 the net settles as under half the displacement, statically."""
    d = [0.0, 0.0, 0.1]
    hist = [[0.0, 0.0], [0.3, 1.0], [0.6, 0.5]]
    data = cable(t_end=5.0)
    data["supports"] = {"move": [{"node": "end", "displacement": d, "history": hist}]}
    scene, result, states = run(data)
    h = History(hist)
    end = scene.net.n_nodes - 1
    for t, x, _ in states[:80]:
        assert np.allclose(x[end], scene.net.nodes[end] + h(t) * np.array(d), atol=1e-12)
    assert scene.loads.settle_time() == 0.6
    static = copy.deepcopy(data)
    static["solver"]["method"] = "static"
    static["supports"] = {"move": [{"node": "end", "displacement": [0.0, 0.0, 0.05]}]}
    _, s, _ = run(static)
    assert result.equilibrium and np.allclose(result.x, s.x, atol=1e-7)


def test_load_history_applies_to_gravity_and_loads_without_their_own():
    data = cable(history=[[0.0, 1.0], [1.0, 2.0]])
    data["load"]["gravity"] = [0, 0, -9.81]
    data["load"]["history"] = [[0.0, 0.0], [1.0, 1.0]]
    data["load"]["point"].append({"node": 2, "force": [1.0, 0.0, 0.0]})
    scene = build(parse_case(data))
    loads, net = scene.loads, scene.net
    weight = net.mass[3] * -9.81
    f = loads.external_force(net, time=0.5)
    assert f[5, 2] == pytest.approx(-1.5 * F + 0.5 * net.mass[5] * -9.81)
    assert f[3, 2] == pytest.approx(0.5 * weight) and f[2, 0] == pytest.approx(0.5)
    full = loads.external_force(net)  # static runs: every load in full
    assert full[5, 2] == pytest.approx(-F + net.mass[5] * -9.81) and full[2, 0] == 1.0
    assert loads.varies and loads.settle_time() == 1.0


def test_set_force_replaces_the_external_force_of_a_potential():
    scene = build(parse_case(cable()))
    ws = workspace(scene, Settings())
    p = ws.potential(scene.loads)
    x = scene.net.nodes.copy()
    f2 = 2.0 * scene.loads.external_force(scene.net)
    p.set_force(f2)
    fresh = ws.potential(scene.loads, factor=2.0)
    assert np.array_equal(p.f_free, fresh.f_free) and p.f_norm == fresh.f_norm
    assert p.evaluate(x).phi == fresh.evaluate(x).phi
    p.set_force(np.zeros_like(f2))
    assert p.external is None and p.f_norm == 0.0


# --------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    ("where", "history", "says"),
    [
        ("point", [[0.0, 0.0], [0.0, 1.0]], "strictly increasing"),
        ("point", [[0.0, 0.0], [1.0, float("nan")]], "finite"),
        ("point", [], "at least one point"),
        ("point", [[0.0, 1.0, 2.0]], "pair"),
        ("line", [[1.0, 0.0], [0.5, 1.0]], "strictly increasing"),
        ("load", [[0.0, float("inf")]], "finite"),
        ("move", [[0.2, 0.0], [0.1, 1.0]], "strictly increasing"),
        ("move", "ramp", "at least one point"),
    ],
)
def test_bad_histories_name_their_key_path(where, history, says):
    data = cable()
    if where == "point":
        data["load"]["point"][0]["history"], path = history, "load.point[0].history"
    elif where == "line":
        data["load"]["line"] = [{"force": [0, 0, -1], "history": history}]
        path = "load.line[0].history"
    elif where == "load":
        data["load"]["history"], path = history, "load.history"
    else:
        data["supports"] = {"move": [{"node": "end", "displacement": [0, 0, 0.1]}]}
        data["supports"]["move"][0]["history"], path = history, "supports.move[0].history"
    with pytest.raises(ConfigError) as err:
        parse_case(data)
    (problem,) = err.value.problems
    assert problem.startswith(f"{path} = ") and says in problem


def test_a_support_move_takes_a_duration_or_a_history_not_both():
    data = cable()
    data["supports"] = {"move": [{"node": "end", "displacement": [0, 0, 0.1], "duration": 1.0,
                                  "history": [[0.0, 0.0], [1.0, 1.0]]}]}  # fmt: skip
    with pytest.raises(ConfigError, match=r"supports.move\[0\].history = .*not both"):
        parse_case(data)


def test_a_bad_history_exits_2_from_the_command_line(write_case, tmp_path):
    text = """
[geometry]
kind = "cable"
start = [0, 0, 0]
end = [1, 0, 0]
nodes = 5
[material]
E = 1e7
radius = 0.01
density = 1000.0
[[load.point]]
node = "midpoint"
force = [0, 0, -1]
history = [[0.0, 0.0], [0.5, 1.0], [0.5, 0.0]]
[solver]
method = "dynamic"
"""
    path = write_case(text)
    out = tmp_path / "o.h5"
    p = subprocess.run(
        catenet_command("run", path, "-o", out), capture_output=True, text=True,
        env=subprocess_env(), timeout=120,
    )  # fmt: skip
    assert p.returncode == 2, p.stderr
    assert "load.point[0].history = [[0.0, 0.0], [0.5, 1.0], [0.5, 0.0]]" in p.stderr
    assert "strictly increasing" in p.stderr and not out.exists()


# --------------------------------------------------------------------------- static runs


def test_static_runs_warn_that_histories_and_velocities_are_ignored(caplog, tmp_path):
    data = cable(method="static", history=[[0.0, 0.0], [1.0, 1.0]])
    data["mass"] = [{"node": 3, "mass": 0.1, "velocity": [0, 0, 1]}]
    case = parse_case(data)
    messages = advice.ignored_histories(case)
    assert len(messages) == 2
    assert messages[0].startswith("load.point[0].history: ignored with solver.method = 'static'")
    assert messages[1].startswith("mass[0].velocity = [0, 0, 1]: ignored")
    from catenet.run.runner import run_case

    with caplog.at_level(logging.WARNING, logger="catenet"):
        result = run_case(case, tmp_path / "static.h5")
    assert any("load.point[0].history: ignored" in r.getMessage() for r in caplog.records)
    # ... and the load acts in full.
    _, plain, _ = run(cable(method="static"))
    assert np.allclose(result.x[[0, 1, 2, 4, 5, 6]], plain.x[[0, 1, 2, 4, 5, 6]], atol=1e-3)


def test_no_warning_without_histories_or_in_dynamic_runs():
    assert advice.ignored_histories(parse_case(cable(method="static"))) == []
    data = cable(history=[[0.0, 0.0], [1.0, 1.0]])
    data["mass"] = [{"node": 3, "velocity": [0, 0, 1]}]
    assert advice.ignored_histories(parse_case(data)) == []


# --------------------------------------------------------------------------- point masses


def net_case(method="static", **mass) -> dict:
    return {
        "geometry": {"kind": "square_net", "n": 6, "alpha": 0.0, "size": 1.0,
                     "edge_length": 0.1, "prestrain": 0.01},
        "material": {"E": 10e6, "radius": 0.01, "density": 1000.0},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "solver": {"method": method, "dt": 0.01, "damping": 5.0, "t_end": 20.0,
                   "rtol": 1e-10},
        **({"mass": [{"node": "center", **mass}]} if mass else {}),
    }  # fmt: skip


def test_gravity_acts_on_a_point_mass_as_a_point_load_m_g():
    """A heavy mass at the centre deflects the net as the point load m g does, statically
    and at the end of a dynamic run."""
    m = 2.0
    scene, with_mass, _ = run(net_case(mass=m))
    c = scene.probe
    assert scene.net.point_mass[c] == m and scene.net.point_mass.sum() == m
    load = net_case()
    load["load"]["point"] = [{"node": "center", "force": [0.0, 0.0, -m * 9.81]}]
    _, with_load, _ = run(load)
    assert with_mass.x[c, 2] < -0.01  # a real deflection, many times the self-weight's
    assert np.allclose(with_mass.x, with_load.x, atol=1e-9)
    _, dyn, _ = run(net_case(method="dynamic", mass=m))
    assert dyn.equilibrium and np.allclose(dyn.x, with_load.x, atol=1e-6)


def test_a_thrown_mass_moves_along_its_velocity_and_the_books_balance():
    """Mass 1 kg at the centre thrown down at 2 m/s, no gravity, no damping: it moves down
    at once; each step's momentum change of the free nodes is h times the support forces
    (Eq. 10a summed), and kinetic plus elastic energy never grows (implicit Euler damps)."""
    data = net_case(method="dynamic", mass=1.0, velocity=[0.0, 0.0, -2.0])
    data["load"] = {}
    data["solver"].update(damping=0.0, t_end=0.3)
    scene = build(parse_case(data))
    net, c = scene.net, scene.probe
    assert scene.velocity[c].tolist() == [0.0, 0.0, -2.0] and not scene.velocity[:c].any()
    ws = workspace(scene, Settings.of(scene.case.solver))
    states = [(0.0, net.nodes.copy(), scene.velocity.copy())]
    solve(scene, Settings.of(scene.case.solver), workspace=ws, start=Start(v=scene.velocity),
          on_step=lambda s: states.append((s.time, s.x.copy(), s.v.copy())))  # fmt: skip
    assert states[1][1][c, 2] < 0.0 and states[1][2][c, 2] < 0.0
    free = ~net.fixed
    energy = []
    for k, (t, x, v) in enumerate(states):
        e_el, grad = ws.system.gradient(x)
        energy.append(e_el + 0.5 * float(np.sum(net.mass[:, None] * v**2)))
        if k:
            h = t - states[k - 1][0]
            dp = (net.mass[free, None] * (v[free] - states[k - 1][2][free])).sum(axis=0)
            support = grad[net.fixed].sum(axis=0)  # = -sum of internal forces on free nodes
            assert np.allclose(dp, h * support, atol=1e-8 * max(1.0, np.abs(dp).max()))
    prestress = ws.system.gradient(net.nodes)[0]
    assert energy[0] == pytest.approx(prestress + 0.5 * net.mass[c] * 4.0)
    assert all(b <= a * (1 + 1e-9) for a, b in zip(energy, energy[1:], strict=False))
    assert energy[-1] < energy[0]


def test_the_runner_starts_dynamic_runs_with_the_velocities(tmp_path):
    from catenet.output.reader import read_frame
    from catenet.run.runner import run_case

    data = net_case(method="dynamic", mass=0.5, velocity=[0.0, 0.0, 1.0])
    data["solver"]["t_end"] = 0.05
    data["output"] = {"file": str(tmp_path / "v.h5")}
    case = parse_case(data)
    run_case(case, str(tmp_path / "v.h5"))
    first, second = read_frame(tmp_path / "v.h5", 0), read_frame(tmp_path / "v.h5", 1)
    c = build(case).probe
    assert first.v[c, 2] == 1.0 and second.x[c, 2] > first.x[c, 2]


@pytest.mark.parametrize(
    ("mass", "says"),
    [
        ({"node": "center"}, "mass[0]: gives neither mass > 0 nor velocity"),
        ({"node": "center", "mass": -1.0}, "mass[0].mass = -1.0: must be finite and >= 0"),
        ({"node": "fixed", "velocity": [0, 0, 1]}, "mass[0].velocity = [0, 0, 1]: node"),
        ({"node": 999, "mass": 1.0}, "mass[0].node = 999: must be a node index in"),
        ({"node": "nowhere", "mass": 1.0}, "mass[0].node = 'nowhere'"),
        ({"mass": 1.0}, "mass[0].node: missing"),
        ({"node": "center", "mass": 1.0, "speed": 1}, "mass[0].speed: unknown key"),
    ],
)  # fmt: skip
def test_bad_masses_name_their_key_path(mass, says):
    data = net_case()
    if mass.get("node") == "fixed":  # the first support
        mass = {**mass, "node": int(np.flatnonzero(build(parse_case(data)).net.fixed)[0])}
    data["mass"] = [mass]
    with pytest.raises(ConfigError) as err:
        build(parse_case(data))
    assert any(p.startswith(says) for p in err.value.problems), err.value.problems


def test_masses_and_histories_survive_the_resolved_case():
    data = cable(history=[[0.0, 0.0], [1.0, 1.0]])
    data["mass"] = [{"node": 3, "mass": 0.2, "velocity": [0, 1, 0]}]
    case = parse_case(data)
    out = case.to_dict()
    assert out["load"]["point"][0]["history"] == [[0.0, 0.0], [1.0, 1.0]]
    assert out["mass"] == [{"node": 3, "mass": 0.2, "velocity": [0.0, 1.0, 0.0]}]
    import tomllib

    again = parse_case(tomllib.loads(case.to_toml()))
    assert again == case


def test_the_readme_example_runs():
    """The TOML example of the time-history section of docs/howto/dynamic-runs.md, on a
    cable."""
    import tomllib
    from pathlib import Path

    page = Path(__file__).resolve().parents[2] / "docs" / "howto" / "dynamic-runs.md"
    text = page.read_text()
    part = text[text.index("## Loads in time, point masses, initial velocities") :]
    example = part[part.index("```toml\n") + 8 : part.index("```\n", part.index("```toml"))]
    data = cable(t_end=0.8)
    data["load"] = {}
    for key, value in tomllib.loads(example).items():
        if isinstance(value, dict):
            data.setdefault(key, {}).update(value)
        else:
            data[key] = value
    scene, result, states = run(data)
    assert scene.net.point_mass[3] == 0.5 and scene.velocity[3, 1] == 2.0
    assert states[0][1][3, 1] > 0.0  # thrown sideways
    assert result.time == pytest.approx(0.8)
    at = {round(t, 6): x for t, x, _ in states}
    end = scene.net.n_nodes - 1
    assert at[0.3][end, 2] == pytest.approx(0.1) and at[0.8][end, 2] == pytest.approx(0.05)
