"""[[supports.vessel]]: a vessel's six rigid motions carry several supports at once
(docs/howto/mooring-dynamics.md): the supports at X + T + (R - I)(X - P) at every step
(R the z-y-x rotation, checked against SciPy's), the smooth start, a static run at
t = 0, the same answer as supports.move for a pure translation, the energy balance of a
heaving support, and bad input's messages."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from scipy.spatial.transform import Rotation

from catenet.case import parse_case
from catenet.case.scene import build
from catenet.cli import main
from catenet.solver.path import Settings, solve


def spread(vessel: dict | None = None, **solver) -> dict:
    """Three short chains hanging from fairleads on a 2 m circle, anchors 8 m out."""
    nodes, cables = [], []
    for k, az in enumerate((0.0, 120.0, 240.0)):
        c, s = math.cos(math.radians(az)), math.sin(math.radians(az))
        nodes += [[10 * c, 10 * s, -8.0], [6 * c, 6 * s, -7.5], [2 * c, 2 * s, -1.0]]
        cables.append({"name": f"line{k}", "nodes": [3 * k, 3 * k + 1, 3 * k + 2]})
    case = {
        "geometry": {
            "kind": "graph",
            "nodes": nodes,
            "edge_length": 1.0,
            "sets": {"anchors": [0, 3, 6], "fairleads": [2, 5, 8]},
            "cable": cables,
        },
        "supports": {"fixed": ["anchors", "fairleads"]},
        "material": {"EA": 1e7, "area": 1e-3, "density": 7850.0, "cd_n": 1.2, "ca_n": 1.0},
        "water": {"density": 1025.0, "surface": 5.0},
        "load": {"gravity": [0, 0, -9.81]},
        "solver": {"method": "dynamic", "dt": 0.02, "t_end": 1.0, **solver},
    }
    if vessel is not None:
        case["supports"]["vessel"] = [vessel]
    return case


def run(case: dict, **keys):
    c = parse_case(case)
    scene = build(c)
    return c, scene, solve(scene, Settings.of(c.solver), **keys)


SINES = [
    {"amplitude": [0.3, 0.2, 0.25, 8.0, 5.0, 10.0], "period": 0.8, "phase": 30.0},
    {"amplitude": [0.1, 0.0, 0.0, 0.0, 2.0, 0.0], "period": 0.5, "phase": [0, 0, 0, 0, 90, 0]},
]
MOTION = [
    [0.0, 0, 0, 0, 0, 0, 0],
    [0.5, 0.4, -0.2, 0.1, 0, 0, 4.0],
    [2.0, 0.4, -0.2, 0.1, 0, 0, 4.0],
]


def expected(t: float, points: np.ndarray, reference, heading: float, ramp: float) -> np.ndarray:
    """The supports at time t, from SciPy's rotations (independent of catenet's)."""
    m = np.zeros(6)
    for k in range(6):
        m[k] = np.interp(t, [r[0] for r in MOTION], [r[k + 1] for r in MOTION])
    for s in SINES:
        phase = np.radians(np.broadcast_to(s["phase"], 6))
        m += np.array(s["amplitude"]) * np.sin(2 * math.pi * t / s["period"] + phase)
    r = 1.0 if t >= ramp else 0.5 * (1 - math.cos(math.pi * t / ramp))
    m *= r
    turn = Rotation.from_euler("z", heading, degrees=True)
    local = Rotation.from_euler("ZYX", [m[5], m[4], m[3]], degrees=True)
    spin = (turn * local * turn.inv()).as_matrix()
    shift = turn.apply(m[:3])
    return points + shift + (points - reference) @ (spin - np.eye(3)).T


def test_the_vessel_carries_its_supports_rigidly_at_every_step():
    """Each step's fairleads are where the vessel's surge..yaw (a table plus two sines,
    turned by the heading, about the reference point, ramped) put them; the anchors
    stay; a static run takes the vessel at t = 0 (the ramp's start: in place)."""
    ref, heading, ramp = [0.5, -0.3, 4.0], 30.0, 0.4
    vessel = {
        "nodes": "fairleads",
        "reference": ref,
        "heading": heading,
        "motion": MOTION,
        "sine": SINES,
        "ramp": ramp,
    }
    seen = []
    c, scene, r = run(spread(vessel), on_step=lambda st: seen.append((st.time, st.x.copy())))
    net = scene.net
    fair = [int(np.argmin(np.linalg.norm(net.nodes - p, axis=1))) for p in net.nodes[net.fixed]]
    fair = [i for i in fair if net.nodes[i, 2] == -1.0]
    anchors = [i for i in np.flatnonzero(net.fixed) if i not in fair]
    assert len(fair) == 3 and len(seen) == 50
    largest = 0.0
    for t, x in seen:
        want = expected(t, net.nodes[fair], np.array(ref), heading, ramp)
        assert np.allclose(x[fair], want, atol=1e-12)
        assert np.allclose(x[anchors], net.nodes[anchors], atol=0)
        largest = max(largest, np.abs(x[fair] - net.nodes[fair]).max())
    assert largest > 0.3  # it moved
    static = spread(vessel, method="static")
    _, sc, rs = run(static)
    assert np.allclose(rs.x[fair], sc.net.nodes[fair], atol=1e-12)


def test_a_pure_translation_is_supports_move():
    """A vessel's surge and heave sine moves its supports as supports.move's sine on
    each of them: the same run, step for step."""
    amp = [0.3, 0.0, 0.2]
    vessel = {"nodes": "fairleads", "sine": [{"amplitude": [*amp, 0, 0, 0], "period": 0.8}]}
    _, _, rv = run(spread(vessel))
    moved = spread()
    moved["supports"]["move"] = [
        {"node": "fairleads", "sine": {"amplitude": amp, "period": 0.8}},
    ]
    _, _, rm = run(moved)
    assert np.allclose(rv.x, rm.x, atol=1e-7)
    assert np.allclose(rv.peaks.tension, rm.peaks.tension, rtol=1e-7)


def rows_of(rows: list):
    return lambda st: rows.append(st.energy)


def test_a_heaving_vessels_energy_balance_closes():
    """Heave and pitch lift the fairleads with their own weight: the work of the
    supports and of the loads at them (the moved nodes' weight) balances what the net
    holds, up to the integrator's own loss (bdf2 here, no drag), which is never a gain
    beyond round-off and shrinks with the step."""
    vessel = {"nodes": "fairleads", "sine": [{"amplitude": [0, 0, 0.5, 0, 6.0, 0], "period": 1.0}]}
    lost = []
    for dt in (0.02, 0.01):
        rows = []
        case = spread(vessel, dt=dt, t_end=1.5, integrator="bdf2")
        case["material"]["cd_n"] = 0.0  # no drag: the balance is the integrator's alone
        run(case, on_step=rows_of(rows))
        work = max(abs(r[3]) for r in rows)
        assert work > 1e3
        lost.append(-min(r[5] for r in rows) / work)
        assert max(r[5] for r in rows) <= 1e-3 * work  # energy never appears
    assert 0.0 < lost[1] < 0.6 * lost[0] < 0.12


@pytest.mark.parametrize(
    ("vessel", "message"),
    [
        ({"nodes": "fairleads"}, "supports.vessel[0]: missing: give motion"),
        (
            {"nodes": "fairleads", "sine": [{"amplitude": [1, 0, 0], "period": 1.0}]},
            "supports.vessel[0].sine[0].amplitude = [1, 0, 0]: must be [surge, sway, heave",
        ),
        (
            {"nodes": "fairleads", "sine": [{"amplitude": [0, 0, 0, 0, 200, 0], "period": 1.0}]},
            "pitch beyond +-180 deg",
        ),
        (
            {"nodes": "fairleads", "motion": [[0, 0, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0, 0]]},
            "supports.vessel[0].motion[1] = [0, 1, 0, 0, 0, 0, 0]: t = 0 does not follow",
        ),
        ({"nodes": "fairleads", "motion": [[0, 1, 2]]}, "supports.vessel[0].motion[0] = [0, 1,"),
        (
            {"nodes": [7], "sine": [{"amplitude": [1, 0, 0, 0, 0, 0], "period": 1.0}]},
            "supports.vessel[0].nodes = 7: is not a fixed node",
        ),
        (
            {
                "nodes": "fairleads",
                "sine": [{"amplitude": [1, 0, 0, 0, 0, 0], "period": 1.0}],
                "ramp": -1,
            },
            "supports.vessel[0].ramp = -1",
        ),
    ],
)
def test_bad_vessel_input_exits_2(tmp_path, vessel, message):
    import tomli_w

    case = spread(vessel)
    path = tmp_path / "case.toml"
    path.write_bytes(tomli_w.dumps(case).encode())
    res = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "o.h5")])
    assert res.exit_code == 2, res.output
    assert message in res.output
    assert "Traceback" not in res.output


def test_a_node_moved_twice_is_refused(tmp_path):
    import tomli_w

    case = spread({"nodes": "fairleads", "sine": [{"amplitude": [1, 0, 0, 0, 0, 0], "period": 1}]})
    case["supports"]["move"] = [{"node": 2, "displacement": [0, 0, 1.0]}]
    path = tmp_path / "case.toml"
    path.write_bytes(tomli_w.dumps(case).encode())
    res = CliRunner().invoke(main, ["run", str(path)])
    assert res.exit_code == 2
    assert "node 2 already moves in supports.move[0]: one move per node" in res.output


WATER_CONFIGS = sorted((Path(__file__).resolve().parents[2] / "configs" / "water").glob("*.toml"))


@pytest.mark.parametrize("path", WATER_CONFIGS, ids=lambda p: p.stem)
def test_the_water_examples_parse_and_build(path):
    """One example per feature in configs/water/ (docs/howto/mooring-dynamics.md): each
    is a sound dynamic case from its equilibrium, its comment says how to run it."""
    from catenet.case import load_case

    c = load_case(path)
    scene = build(c)
    assert c.solver.method == "dynamic" and c.solver.initial_state == "equilibrium"
    assert c.water is not None and scene.net.n_edges > 10
    assert "Run: catenet run configs/water/" in path.read_text()
