"""A dynamic run's /history (contract §7): a row at every time step; the last row is
/result's reactions and contact forces; the momentum of the net and its bodies changes
by the applied loads, reactions and contact forces of the rows, step by step; a restart
goes on with the earlier rows; a stopped run keeps its rows; ``catenet plot --history``
draws them."""

from __future__ import annotations

import h5py
import numpy as np
import pytest
from click.testing import CliRunner
from meshes import net_under_gravity

from catenet.case import build, dumps_toml, parse_case
from catenet.cli import main
from catenet.output.history import read_history
from catenet.run.runner import run_case

G = 9.81


def drop(t_end: float = 0.2, **solver) -> dict:
    """A pinned square net under gravity, a free capsule (a body) falling onto it and a
    fixed sphere beside it that nothing touches; every step a frame."""
    return {
        **net_under_gravity(6, 0.1),
        "obstacle": [
            {
                "kind": "capsule", "start": [-0.2, 0.0, 0.12], "end": [0.2, 0.0, 0.12],
                "radius": 0.06, "density": 800.0, "velocity": [0.0, 0.0, -1.5],
                "angular_velocity": [0.0, 1.0, 0.5],
            },
            {"kind": "sphere", "center": [3.0, 3.0, 3.0], "radius": 0.2},
        ],
        "solver": {
            "method": "dynamic", "dt": 0.005, "damping": 0.0, "t_end": t_end,
            "integrator": "implicit_euler", **solver,
        },
        "output": {"every": 1},
    }  # fmt: skip


@pytest.fixture(scope="module")
def dropped(tmp_path_factory):
    out = tmp_path_factory.mktemp("history") / "drop.h5"
    case = drop()
    res = run_case(parse_case(case), out)
    return case, out, res


def test_every_step_has_a_row_and_the_last_is_the_result(dropped):
    case, out, res = dropped
    hist = read_history(out)
    with h5py.File(out) as f:
        fixed = np.flatnonzero(f["mesh/fixed"][:])
        n_net = len(f["mesh/nodes"]) - 4  # the capsule's four nodes last
        assert np.asarray(f["trajectory/time"]) == pytest.approx(hist.time, abs=1e-12)
        reaction = np.asarray(f["result/reaction"])[fixed]
        contact = np.asarray(f["result/contact_force"])[:n_net].sum(axis=0)
        assert f["history/contact"].attrs["kinds"].tolist() == ["capsule", "sphere"]
    assert len(hist.time) == res.steps + 1  # the start, then every step
    assert np.all(np.diff(hist.time) > 0)
    assert hist.names == ["obstacle[0]", "obstacle[1]"]
    assert hist.reaction_nodes.tolist() == fixed.tolist()
    scale = np.abs(reaction).max()
    assert np.abs(hist.reaction[-1] - reaction).max() <= 1e-9 * scale
    assert np.abs(hist.contact[-1].sum(axis=0) - contact).max() <= 1e-9 * scale
    assert np.abs(hist.contact[:, 1]).max() == 0.0  # the sphere nothing touches
    assert np.abs(hist.contact[:, 0, 2]).max() > 0.1 * scale  # the capsule lands


def test_momentum_changes_by_loads_reactions_and_contact_at_every_step(dropped):
    case, out, _ = dropped
    scene = build(parse_case(case))
    hist = read_history(out)
    with h5py.File(out) as f:
        m = np.asarray(f["mesh/mass"])
        free = ~np.asarray(f["mesh/fixed"])
        v = np.asarray(f["trajectory/v"])
    t = hist.time
    h = np.diff(t)[:, None]
    momentum = np.einsum("n,snk->sk", m * free, v)  # net and body
    body = np.einsum("n,snk->sk", m[-4:], v[:, -4:])  # the capsule alone
    loads = np.array([scene.loads.external_force(scene.net, time=s).sum(axis=0) for s in t[1:]])
    # implicit Euler: m (v' - v) / h = forces at the step's end
    change = np.diff(momentum, axis=0) / h
    balance = loads + hist.reaction[1:].sum(axis=1) + hist.contact[1:, 1]
    scale = np.abs(balance).max()
    assert np.abs(change - balance).max() <= 1e-5 * scale
    # the capsule: its weight, less the force it exerts on the net
    weight = np.array([0.0, 0.0, -G * m[-4:].sum()])
    landed = np.diff(body, axis=0) / h
    assert np.abs(landed - (weight - hist.contact[1:, 0])).max() <= 1e-5 * scale
    assert np.abs(hist.contact[:, 0]).max() > 0.1 * scale  # it lands, within the run


def test_a_restart_goes_on_with_the_earlier_rows(dropped, tmp_path):
    case, full, _ = dropped
    first, second = tmp_path / "first.h5", tmp_path / "second.h5"
    run_case(parse_case(drop(t_end=0.1)), first)
    run_case(parse_case(case), second, restart=first)
    a, b = read_history(full), read_history(second)
    assert b.time == pytest.approx(a.time, abs=1e-12)  # no row twice, none missing
    scale = np.abs(a.reaction).max()
    assert np.abs(b.reaction - a.reaction).max() <= 1e-5 * scale
    assert np.abs(b.contact - a.contact).max() <= 1e-5 * scale


@pytest.mark.parametrize("damage", ["removed", "cut", "nan"])
def test_a_restart_from_a_damaged_history_begins_it_anew(dropped, tmp_path, damage):
    """The fuzz tests' draw: a restart from a file whose /history/reaction was removed
    stopped with an internal error (the rows' shape checked only on writing). A column
    missing, shorter than its times or not finite: the run goes on, its history begins
    at the restart."""
    case, _, _ = dropped
    first, second = tmp_path / "first.h5", tmp_path / "second.h5"
    run_case(parse_case(drop(t_end=0.1)), first)
    with h5py.File(first, "a") as f:
        rows = np.asarray(f["history/reaction"])
        del f["history/reaction"]
        if damage == "cut":
            f["history/reaction"] = rows[:3]
        elif damage == "nan":
            f["history/reaction"] = np.where(np.arange(len(rows))[:, None, None] == 5, np.nan, rows)
    res = run_case(parse_case(case), second, restart=first)
    hist = read_history(second)
    assert res.converged and len(hist.time) > 0
    assert hist.time[0] > 0.1 - 1e-9  # the earlier rows left out, this run's kept
    assert np.all(np.isfinite(hist.reaction))


def test_a_stopped_run_keeps_its_rows(tmp_path):
    out = tmp_path / "stopped.h5"
    seen = []

    def stop() -> bool:
        seen.append(1)
        return len(seen) >= 12

    res = run_case(parse_case({**drop(), "output": {"every": 5}}), out, stop=stop)
    hist = read_history(out)
    assert not res.converged and res.steps == 12
    assert len(hist.time) == 13 and hist.time[-1] == pytest.approx(res.time)
    with h5py.File(out) as f:
        reaction = np.asarray(f["result/reaction"])[hist.reaction_nodes]
    assert hist.reaction[-1] == pytest.approx(reaction, rel=1e-9, abs=1e-12)


def test_a_run_interrupted_within_a_step_keeps_its_rows_to_the_last_good_state(tmp_path):
    out = tmp_path / "interrupted.h5"
    asked = []

    def interrupt() -> bool:  # asked before every Newton iteration
        asked.append(1)
        return len(asked) >= 40

    res = run_case(parse_case({**drop(), "output": {"every": 0}}), out, interrupt=interrupt)
    hist = read_history(out)
    assert not res.converged and 0 < res.steps < 40
    assert len(hist.time) == res.steps + 1 and hist.time[-1] == pytest.approx(res.time)
    with h5py.File(out) as f:
        reaction = np.asarray(f["result/reaction"])[hist.reaction_nodes]
    assert hist.reaction[-1] == pytest.approx(reaction, rel=1e-9, abs=1e-12)


def test_named_cables_keep_the_tension_of_their_end_edges(tmp_path):
    case = {
        "geometry": {
            "kind": "graph", "nodes": [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
            "cable": [{"name": "line", "nodes": [0, 1], "edge_length": 0.25}],
            "sets": {"anchors": [0, 1], "left": [0]},
        },
        "material": {"E": 1e9, "radius": 0.002, "density": 1000.0},
        "supports": {"fixed": [0], "spring": [{"nodes": [1], "stiffness": [1e5, 1e5, 1e5]}]},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "solver": {"method": "dynamic", "dt": 0.01, "t_end": 0.1, "damping": 1.0},
        "output": {"every": 0},
    }  # fmt: skip
    out = tmp_path / "cable.h5"
    run_case(parse_case(case), out)
    hist = read_history(out)
    assert hist.cable_names == ["line"] and len(hist.time) == 11
    with h5py.File(out) as f:
        edges = f["history/cable_end_tension"].attrs["edges"]
        tension = np.asarray(f["result/tension"])
        assert "trajectory" not in f
    assert edges.tolist() == [[0, 7]]
    assert hist.cable_end_tension[-1, 0] == pytest.approx(tension[[0, 7]], rel=1e-12)
    assert hist.reaction_nodes.tolist() == [0, 1]  # the fixed node and the spring's
    with h5py.File(out) as f:
        reaction = np.asarray(f["result/reaction"])[[0, 1]]
    assert np.abs(reaction[1]).max() > 1.0  # the spring holds
    assert hist.reaction[-1] == pytest.approx(reaction, rel=1e-9, abs=1e-9)
    assert hist.contact.shape == (11, 0, 3)
    # the figure: reactions per support set, the cable's ends
    from catenet.plot.history import history_figure, support_sets

    sets = support_sets(out, hist.reaction_nodes)
    assert {k: v.tolist() for k, v in sets.items()} == {"anchors": [0, 1], "left": [0]}
    axes = {ax.get_label(): ax for ax in history_figure(hist, sets).axes}
    assert set(axes) == {"reactions", "cable end tensions"}
    lines = [line.get_label() for line in axes["reactions"].get_lines()]
    assert lines == ["resultant Rx", "resultant Ry", "resultant Rz", "|R| anchors", "|R| left"]
    anchors = axes["reactions"].get_lines()[3].get_ydata()
    weight = np.linalg.norm(hist.reaction.sum(axis=1), axis=1)
    assert anchors == pytest.approx(weight)
    assert axes["cable end tensions"].get_ylabel() == "tension [N]"
    assert axes["cable end tensions"].get_xlabel() == "t [s]"


def test_plot_history_draws_the_rows_and_refuses_a_static_file(dropped, tmp_path):
    from catenet.plot.history import history_figure

    _, out, _ = dropped
    fig = history_figure(read_history(out))
    labels = {ax.get_label(): ax for ax in fig.axes}
    assert set(labels) == {"reactions", "contact"}
    assert labels["reactions"].get_ylabel() == "reaction [N]"
    assert labels["contact"].get_ylabel() == "contact force [N]"
    assert labels["contact"].get_xlabel() == "t [s]"
    png = tmp_path / "h.png"
    res = CliRunner().invoke(main, ["plot", str(out), "--history", "-o", str(png)])
    assert res.exit_code == 0, res.output
    assert png.stat().st_size > 10_000 and res.output.strip() == str(png)
    static = {**net_under_gravity(4, 0.2), "solver": {"method": "static"}}
    path = tmp_path / "static.toml"
    path.write_text(dumps_toml(static))
    h5 = tmp_path / "static.h5"
    assert CliRunner().invoke(main, ["run", str(path), "-o", str(h5)]).exit_code == 0
    with h5py.File(h5) as f:
        assert "history" not in f
    res = CliRunner().invoke(main, ["plot", str(h5), "--history"])
    assert res.exit_code == 2
    assert res.output.count("error") == 1 and "no /history (a static run's)" in res.output
    res = CliRunner().invoke(main, ["plot", str(tmp_path), "--history"])
    assert res.exit_code == 2 and "not a directory" in res.output
