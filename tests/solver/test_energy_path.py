"""The energy verdict of runs with a ball on a prescribed path: the path's work on the
net through the spring that holds the ball on it is booked (``external_work``,
``catenet.terms.body.Guide.driven_work``) and the balance is judged as in any other run
(before, such runs were not judged). A ball pressed into a net along a path and held
there balances to a small share of the energy it moved; newmark gaining energy where the
ball hits the net is stopped by the verdict."""

from __future__ import annotations

import numpy as np
import pytest

import catenet as cn
from catenet.case import build, parse_case
from catenet.solver.energy import EnergyError
from catenet.terms.body import Guide, Path

#: A square net of 1 m (10 cables, prestrain 1e-2) and a ball of 0.15 m brought down
#: 0.15 m along a path into its middle, its speed ramped up and down, then held there.
NET = {
    "title": "a ball pressed into a net along a path",
    "geometry": {
        "kind": "square_net",
        "n": 10,
        "alpha": 0.0,
        "size": 1.0,
        "edge_length": 0.1,
        "prestrain": 0.01,
    },
    "material": {"E": 1e8, "radius": 0.004, "density": 1100.0},
    "obstacle": [
        {
            "kind": "sphere",
            "center": [0.0, 0.0, 0.17],
            "radius": 0.15,
            "velocity": [0.0, 0.0, -1.0],
            "history": [[0.0, 0.0], [0.05, 1.0], [0.15, 1.0], [0.2, 0.0]],
            "distance": 0.005,
        }
    ],
    "solver": {"method": "dynamic", "dt": 0.005, "t_end": 0.4, "damping": 0.0},
}


def _solve(solver: dict):
    scene = build(parse_case({**NET, "solver": {**NET["solver"], **solver}}))
    assert any(isinstance(t, Guide) for t in scene.terms)
    return scene, cn.solve(scene, cn.Settings.of(scene.case.solver))


@pytest.mark.parametrize("integrator", ["bdf2", "implicit_euler"])
def test_a_ball_pressed_into_a_net_along_a_path_balances(integrator):
    """The path's work (15 J: what the net holds when the ball stops, 0.13 m into it,
    less its prestrain's 3.6 J) is booked; the remainder, the integrator's own loss, is
    a small share of it (bdf2 0.3 %, implicit Euler 0.9 %), and the run is judged."""
    scene, result = _solve({"integrator": integrator})
    assert result.converged, result.message
    kinetic, elastic, contact, work, lost, numerical = result.energy
    assert work > 10.0
    assert numerical <= 0.0 and abs(numerical) < 0.02 * work, result.energy
    sag = scene.net.nodes[:, 2].max() - result.x[: scene.net.n_nodes - 1, 2].min()
    assert sag > 0.1


def test_the_paths_work_is_the_force_on_the_ball_times_the_paths_displacement():
    """The booking of two steps by hand: the first the end's force on the ball times the
    anchor's displacement (the spring holds nothing at the start: the ball's weight and
    the net's push come within the step's first instants), then the trapezoid of the
    spring's force at the step's start and end; a static load step books nothing. A step
    judged before it is taken (``commit=False``) books the same and keeps nothing."""
    path = Path(np.zeros(3), np.array([0.0, 0.0, -1.0]))
    guide = Guide(0, path, 1e3, n_nodes=1)
    x0, x1, x2 = (np.array([[0.0, 0.0, z]]) for z in (0.0, -0.09, -0.19))
    guide.begin_run(x0, 0.0)
    guide.begin_step(x0, 0.1, 0.0)
    f1 = -1e3 * (x1[0] - path(0.1))
    for commit in (False, True):  # judged, then taken: both the first step's booking
        assert guide.driven_work(x0, x1, commit) == pytest.approx(f1 @ (path(0.1) - path(0.0)))
    guide.begin_step(x1, 0.2, 0.1)
    f2 = -1e3 * (x2[0] - path(0.2))
    assert guide.driven_work(x1, x2) == pytest.approx(0.5 * (f1 + f2) @ (path(0.2) - path(0.1)))
    assert guide.driven_work(x1, x2) == pytest.approx(1.0)  # 10 N against 0.1 m
    guide.begin_step(x2, None)  # a static load step: no time, no work
    assert guide.driven_work(x1, x2) == 0.0


@pytest.mark.parametrize("speed", [2.0, 3.0])
def test_newmark_gaining_energy_where_a_path_ball_hits_the_net_is_stopped(speed):
    """Newmark (rho_inf 0.95, undamped), refused in contact by a case file, through
    Python's solve: the ball comes down at constant speed onto the net and the
    integrator creates energy; the verdict stops it (before: not judged, an answer).
    Each step's Newton held to 25 iterations: with more, at 3 m/s, its steps converge
    where they were cut, and newmark loses energy there instead (which the verdict lets
    pass, as numerical damping). The net's nodes are moved by 1e-6 of its size (seeded):
    newmark's energy grows in a motion that breaks the net's symmetry, and from the
    exactly symmetric start whether it starts within the run hung on the processor's
    round-off (3 m/s lost half its energy on one, gained on another); moved, every seed
    and speed tried gains on 1 and 2 threads."""
    data = {**NET, "obstacle": [{k: v for k, v in NET["obstacle"][0].items() if k != "history"}]}
    data["obstacle"][0]["velocity"] = [0.0, 0.0, -speed]
    scene = build(parse_case(data))
    nodes = scene.net.nodes
    nodes += (
        1e-6 * np.ptp(nodes, axis=0).max() * np.random.default_rng(3).uniform(-1, 1, nodes.shape)
    )
    settings = cn.Settings.of(scene.case.solver, integrator="newmark", rho_inf=0.95, max_iter=25)
    with pytest.raises(EnergyError, match="the integrator creates energy"):
        cn.solve(scene, settings)
