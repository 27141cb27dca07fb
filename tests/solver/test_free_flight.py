"""A net without supports in a dynamic run (it flies free, contract §7): thrown at a free
box in zero gravity without damping, net and box together keep their linear momentum to
the solver's tolerance at every step, and their angular momentum drifts less as the
step shrinks under newmark; the net never enters the box; a static run of a net without
supports is refused (it would move as a rigid body), exit 2."""

from __future__ import annotations

import math

import numpy as np
import pytest

from catenet.case import build, dumps_toml, parse_case
from catenet.solver.path import Settings, solve
from catenet.terms.rigid_contact import BodyContact


def thrown_net(n: int = 5, **solver) -> dict:
    """An n x n square net of 0.5 m thrown down at 2 m/s (and turning) at a 4 kg box."""
    g = np.linspace(-0.25, 0.25, n)
    nodes = [[float(x), float(y), 0.25] for y in g for x in g]
    edges = [[j * n + i, j * n + i + 1] for j in range(n) for i in range(n - 1)]
    edges += [[j * n + i, (j + 1) * n + i] for j in range(n - 1) for i in range(n)]
    speed = [[0.3 * y, -0.3 * x, -2.0] for x, y, _ in nodes]  # a spin about z
    return {
        "geometry": {"kind": "graph", "nodes": nodes, "edges": edges},
        "material": {"E": 2e9, "radius": 0.001, "density": 1000.0, "tension_only": False},
        "mass": [{"node": i, "mass": 0.05, "velocity": v} for i, v in enumerate(speed)],
        "obstacle": [
            {
                "kind": "box", "center": [0.02, -0.01, 0.0], "half_size": [0.15, 0.12, 0.1],
                "angle": 0.3, "mass": 4.0, "angular_velocity": [0.0, 0.5, 0.2],
                "distance": 0.005,
            }
        ],
        "solver": {"method": "dynamic", "damping": 0.0, "t_end": 0.2, **solver},
    }  # fmt: skip


def momenta(scene, x, v):
    m = scene.net.mass[:, None]
    return (m * v).sum(axis=0), (m * np.cross(x, v)).sum(axis=0)


def run(case, **keys):
    """The run of ``case`` (``keys``: [solver] keys changed in Python, where newmark,
    which a case file with contact refuses, is still taken)."""
    scene = build(parse_case(case))
    contact = next(t for t in scene.terms if isinstance(t, BodyContact))
    p0, L0 = momenta(scene, scene.net.nodes, scene.velocity)
    rows = []

    def on_step(s):
        rows.append((*momenta(scene, s.x, s.v), float(contact.gap(s.x).min())))

    r = solve(scene, Settings.of(scene.case.solver, **keys), on_step=on_step)
    assert r.converged
    return scene, p0, L0, rows


def test_a_free_net_and_a_free_box_keep_their_momentum():
    scene, p0, L0, rows = run(thrown_net(dt=0.005))
    assert not scene.net.fixed.any()
    gaps = [row[2] for row in rows]
    assert min(gaps) > 0.0 and min(gaps) < 0.005  # they met, and nothing went in
    scale = float(np.linalg.norm(p0))
    assert max(float(np.abs(p - p0).max()) for p, _, _ in rows) < 1e-7 * scale
    # Angular momentum: newmark keeps it to a drift that falls with the step (the
    # contact's impulse is not resolved by the step, so not at a clean order). Newmark
    # creates energy in this contact (8 % by t = 0.08 s at rho_inf = 0.9), which a run
    # refuses by default (tests/solver/test_energy.py): the momenta are measured with
    # that check off.
    m = scene.net.mass[:, None]
    scale = float(
        (m * np.linalg.norm(np.cross(scene.net.nodes, scene.velocity), axis=1)[:, None]).sum()
    )
    drifts = {}
    for dt in (0.004, 0.002):
        case = thrown_net(dt=dt, t_end=0.12, energy_tolerance=1e9)
        _, _, L0, rows = run(case, integrator="newmark", rho_inf=0.9)
        drifts[dt] = max(float(np.linalg.norm(L - L0)) for _, L, _ in rows)
    assert drifts[0.004] < 2e-3 * scale and drifts[0.002] < 0.5 * drifts[0.004]


def test_a_static_run_of_a_net_without_supports_is_refused(tmp_path):
    from click.testing import CliRunner

    from catenet.cli import main

    case = thrown_net()
    case.pop("obstacle")
    case["solver"] = {"method": "static"}
    for m in case["mass"]:
        m.pop("velocity")
    path = tmp_path / "case.toml"
    path.write_text(dumps_toml(case))
    res = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "out.h5")])
    assert res.exit_code == 2, res.output
    assert "geometry.fixed: missing or empty" in res.output
    assert "moves as a rigid body" in res.output and "solver.method = 'dynamic'" in res.output


@pytest.mark.parametrize("method", ["dynamic"])
def test_a_free_net_alone_flies_straight(method):
    """No body, no loads: every node keeps its velocity (the net's own forces are
    internal); the regularisation pins nothing."""
    case = thrown_net()
    case.pop("obstacle")
    for m in case["mass"]:
        m["velocity"] = [1.0, -0.5, 0.25]
    scene = build(parse_case(case))
    r = solve(scene, Settings.of(scene.case.solver))
    assert r.converged
    assert r.x - scene.net.nodes == pytest.approx(np.full_like(r.x, 0.2) * [1.0, -0.5, 0.25])
    assert r.v == pytest.approx(np.tile([1.0, -0.5, 0.25], (len(r.x), 1)))


@pytest.mark.parametrize("dt", [0.1, 0.01, 0.001])
def test_no_node_enters_the_box_at_any_step_size(dt):
    """The thrown net at steps from 1e-3 to 1e-1 s: every accepted state has every node
    outside the box, and so has every point of the straight motion between two of them
    (sampled densely)."""
    case = thrown_net(dt=dt)
    case["solver"]["t_end"] = 0.2
    scene = build(parse_case(case))
    contact = next(t for t in scene.terms if isinstance(t, BodyContact))
    states = [scene.net.nodes.copy()]
    r = solve(scene, Settings.of(scene.case.solver), on_step=lambda s: states.append(s.x.copy()))
    assert r.converged
    worst = math.inf
    for a, b in zip(states[:-1], states[1:], strict=True):
        for s in np.linspace(0.0, 1.0, 11):
            worst = min(worst, float(contact.gap(a + s * (b - a)).min()))
    assert 0.0 < worst < contact.dhat  # touching, never inside
