"""The nested start (catenet.solver.nested): Newton iterations on the fine net that do not
grow with refinement, the default start's equilibrium, the default start untouched where
``auto`` does not nest, and bad input where ``solver.start = "nested"`` cannot apply."""

from __future__ import annotations

import dataclasses
import tomllib

import numpy as np
import pytest
from conftest import CONFIGS
from meshes import hypar_roof

from catenet.case import build, load_case, parse_case
from catenet.errors import ConfigError
from catenet.scene import Scene
from catenet.solver import nested
from catenet.solver import path as sv

N10 = CONFIGS / "fig4a_n10_alpha_0.toml"
N34 = CONFIGS / "fig4g_n34_alpha_0.toml"


def scene(path, *overrides):
    case = load_case(path, list(overrides))
    return build(case), sv.Settings.of(case.solver)


def solve(path, start, *overrides):
    s, settings = scene(path, *overrides)
    return s, sv.solve(s, dataclasses.replace(settings, start=start))


def test_iterations_do_not_grow_with_refinement():
    """n = 10 at 1 cm, 5 mm and 2.5 mm edges: the stretched start takes 7, 7, 9 Newton
    iterations, the nested start 3, 3, 2 on the fine net (after 7 on the coarse one)."""
    fine, coarse, stretched = [], [], []
    for edge in (0.01, 0.005, 0.0025):
        s, r = solve(N10, "nested", f"geometry.edge_length={edge}")
        assert r.converged and r.nested is not None
        assert r.nested.factor == 2.0 and r.nested.dofs < nested.free_dofs(s.net)
        fine.append(r.iterations)
        coarse.append(r.nested.iterations)
        stretched.append(solve(N10, "stretched", f"geometry.edge_length={edge}")[1].iterations)
    assert fine == sorted(fine, reverse=True), fine  # never more on a finer net
    assert max(fine) <= 3 < min(stretched), (fine, stretched)
    assert stretched[-1] > stretched[0]  # what the nested start is for
    assert all(c > 0 for c in coarse)


@pytest.mark.parametrize(
    "path, overrides",
    [
        (N10, ("geometry.edge_length=0.004",)),
        (CONFIGS / "fig4h_n34_alpha_pi6.toml", ("geometry.edge_length=0.008", "solver.steps=3")),
    ],
)
def test_the_same_equilibrium_as_the_default_start(path, overrides):
    tight = ("solver.rtol=1e-12", *overrides)
    s, a = solve(path, "stretched", *tight)
    _, b = solve(path, "nested", *tight)
    assert a.converged and b.converged and b.nested is not None and a.steps == b.steps
    scale = np.max(np.abs(a.x - s.net.nodes))
    assert np.max(np.abs(a.x - b.x)) <= 1e-9 * scale
    assert np.max(np.abs(a.tension - b.tension)) <= 1e-9 * np.max(a.tension)


def test_cables_with_an_edge_length():
    """A flat graph of cables (a hypar plan, unstressed) under a plan load: the coarse net
    is the case at longer edges; the same equilibrium as from the stretched start."""
    data = hypar_roof(rise=0.0, cells=3, edge_length=0.25)
    data["material"] = {"EA": 1e6}
    data["load"] = {"area": [{"pressure": 500.0}]}
    data["solver"] = {"rtol": 1e-12}
    s = build(parse_case(data))
    settings = sv.Settings.of(parse_case(data).solver)
    a = sv.solve(s, dataclasses.replace(settings, start="stretched"))
    b = sv.solve(s, dataclasses.replace(settings, start="nested"))
    assert b.nested is not None and b.nested.dofs < nested.free_dofs(s.net)
    assert b.iterations < a.iterations
    scale = np.max(np.abs(a.x - s.net.nodes))
    assert np.max(np.abs(a.x - b.x)) <= 1e-9 * scale


def test_auto_leaves_the_paper_nets_to_the_stretched_start():
    """Below NESTED_DOFS (the paper's 1 cm nets) "auto" is the stretched start, the same
    solve; above it a net nests (NESTED_DOFS lowered here to keep the test small)."""
    s, settings = scene(N34)
    assert nested.free_dofs(s.net) < nested.NESTED_DOFS
    auto = sv.solve(s, settings)
    stretched = sv.solve(s, dataclasses.replace(settings, start="stretched"))
    assert auto.nested is None and auto.iterations == stretched.iterations == 7
    # (two runs of one solve agree to round-off, not always bit for bit: the backend's)
    assert np.max(np.abs(auto.x - stretched.x)) <= 1e-12 * np.max(np.abs(s.net.nodes))
    s, settings = scene(N10, "geometry.edge_length=0.004")
    assert nested.coarse_factor(s, settings, False) is None
    saved = nested.NESTED_DOFS
    try:
        nested.NESTED_DOFS = nested.free_dofs(s.net)
        assert nested.coarse_factor(s, settings, False) == 2.0
        assert nested.coarse_factor(s, settings, True) is None  # a given start
        prestressed, p_settings = scene(
            N10, "geometry.edge_length=0.004", "geometry.prestrain=0.01"
        )
        assert nested.coarse_factor(prestressed, p_settings, False) is None  # not flat
    finally:
        nested.NESTED_DOFS = saved


def test_a_load_case_from_the_base_state_is_not_nested():
    s, settings = scene(N10)
    base = sv.solve(s, settings)
    r = sv.solve(
        Scene(s.net, s.loads),
        dataclasses.replace(settings, start="nested"),
        start=sv.Start(x=base.x),
    )
    assert r.nested is None and r.iterations <= 1


def test_where_the_nested_start_cannot_apply():
    with pytest.raises(ConfigError, match=r'solver.start = "nested": needs a net discretised'):
        solve(CONFIGS / "catenary.toml", "nested")
    with pytest.raises(ConfigError, match="supports.fixed|node by an index"):
        solve(N10, "nested", "supports.fixed=[0, 1, 2, 3]")
    data = tomllib.loads(N10.read_text())
    data["obstacle"] = [{"kind": "plane", "point": [0, 0, -1.0], "normal": [0, 0, 1.0]}]
    data["solver"]["start"] = "nested"
    with pytest.raises(ConfigError, match="obstacles, bodies, rods or self-contact"):
        s = build(parse_case(data))
        sv.solve(s, sv.Settings.of(parse_case(data).solver))
    with pytest.raises(ConfigError, match="static runs"):
        sv.Settings(method="dynamic", start="nested")
    with pytest.raises(ConfigError, match="solver.start = 'coarse': must be one of"):
        sv.Settings(start="coarse")


def test_a_coarse_net_that_does_not_match_falls_back(monkeypatch, caplog):
    """Where the coarse state does not carry over (here: made so), the default start,
    said in the log; the iterations are the stretched start's."""
    monkeypatch.setattr(sv, "transfer", lambda *a: None)
    s, r = solve(N10, "nested", "geometry.edge_length=0.005")
    assert r.converged and r.nested is None and r.iterations == 7
    assert "does not match" in caplog.text


def test_an_interrupted_coarse_solve_keeps_the_fine_nets_start(monkeypatch):
    """The coarse net's solve interrupted (its last good state is a state of the coarse
    net, fewer nodes): the run's last good state is the fine net's start at load factor
    0, of the fine net's shape (the coarse one's would be written as this net's)."""
    from catenet.errors import Interrupted, LastGood, with_last_good

    s, settings = scene(N10, "geometry.edge_length=0.005")
    real = sv.solve

    def coarse_interrupted(coarse, *args, **kwargs):
        assert coarse.net.n_nodes < s.net.n_nodes
        stop = Interrupted("interrupted", iterations=3)
        raise with_last_good(stop, LastGood(coarse.net.nodes.copy(), 0.5))

    monkeypatch.setattr(sv, "solve", coarse_interrupted)
    with pytest.raises(Interrupted) as stopped:
        real(s, dataclasses.replace(settings, start="nested"))
    good = stopped.value.last_good
    assert good.time == 0.0 and good.x.shape == s.net.nodes.shape
