"""catenet plot RESULT.h5 --case NAME | --time T | --frame K: the figure draws that state
(its positions, tensions and reactions as the file holds them, read here with h5py), says
which it is, and a name, time or frame the file does not have exits 2 with one message
that lists what it has."""

from __future__ import annotations

import h5py
import numpy as np
import pytest
from click.testing import CliRunner
from conftest import CONFIGS

from catenet.cli import main
from catenet.output import read_result
from catenet.plot.figure import figure
from catenet.plot.state import select

MAST = CONFIGS / "structures" / "mast_load_cases.toml"

SWING = """
title = "a swinging cable"
[geometry]
kind = "cable"
start = [0.0, 0.0, 0.0]
end = [4.0, 0.0, 0.0]
length = 4.4
nodes = 9
[material]
EA = 2.0e5
radius = 0.005
density = 7800.0
[load]
gravity = [0.0, 0.0, -9.81]
[solver]
method = "dynamic"
dt = 0.01
damping = 0.5
t_end = 0.3
"""


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.fixture(scope="module")
def mast(tmp_path_factory):
    out = tmp_path_factory.mktemp("mast") / "mast.h5"
    res = invoke("run", MAST, "-o", out, "-q")
    assert res.exit_code == 0, res.output
    return out


@pytest.fixture(scope="module")
def swing(tmp_path_factory):
    d = tmp_path_factory.mktemp("swing")
    (d / "swing.toml").write_text(SWING)
    res = invoke("run", d / "swing.toml", "-o", d / "swing.h5", "-q")
    assert res.exit_code == 0, res.output
    return d / "swing.h5"


def panel(fig, title):
    return next(ax for ax in fig.axes if ax.get_title() == title)


def deformed(fig):
    """The side view's deformed edges: their segments (x-z) and colour values."""
    side = panel(fig, "side view")
    lines = next(c for c in side.collections if c.get_label() == "deformed")
    return np.asarray(lines.get_segments()), np.asarray(lines.get_array())


def test_a_combination_is_drawn_from_its_group(mast):
    res = read_result(mast)
    chosen, shown, note = select(res, case="ULS_diagonal")
    assert note == "" and shown is not None and shown.label == "combination ULS_diagonal"
    fig = figure(chosen, shown=shown)
    with h5py.File(mast) as h5:
        g = h5["cases/ULS_diagonal"]
        x, t, r = g["x"][()], g["tension"][()], g["reaction"][()]
        edges, fixed = h5["mesh/edges"][()], h5["mesh/fixed"][()]
    segments, colours = deformed(fig)
    np.testing.assert_array_equal(segments, x[edges][:, :, [0, 2]])
    np.testing.assert_array_equal(colours, t)
    assert fig.get_suptitle().endswith(": combination ULS_diagonal")
    # the plan view's arrows: the combination's reactions, not the base state's
    quiver = next(c for c in panel(fig, "plan view").collections if type(c).__name__ == "Quiver")
    h = r[fixed][:, :2]
    scale = quiver.U[np.argmax(np.abs(quiver.U))] / h[np.argmax(np.abs(h[:, 0])), 0]
    np.testing.assert_allclose(quiver.U, scale * h[:, 0], rtol=1e-12)
    # no time panel: a case is solved from the base state, its path is not stored
    assert "probe displacement against load" not in [a.get_title() for a in fig.axes]


def test_the_envelope_colours_by_the_largest_tension_and_displacement(mast):
    res = read_result(mast)
    chosen, shown, _ = select(res, case="envelope")
    fig = figure(chosen, shown=shown)
    with h5py.File(mast) as h5:
        t_max = h5["envelope/tension_max"][()]
        u_max = h5["envelope/displacement_max"][()]
        x = h5["result/x"][()]
        edges = h5["mesh/edges"][()]
    segments, colours = deformed(fig)
    np.testing.assert_array_equal(colours, t_max)
    np.testing.assert_array_equal(segments, x[edges][:, :, [0, 2]])  # on the base state
    plan = panel(fig, "plan view")
    lines = next(c for c in plan.collections if c.get_array() is not None)
    np.testing.assert_allclose(lines.get_array(), 0.5 * (u_max[edges[:, 0]] + u_max[edges[:, 1]]))
    bars = [a.get_xlabel() for a in fig.axes]
    assert f"largest displacement of the cases [m], up to {u_max.max():.4g}" in bars
    (side,) = [a.get_ylabel() for a in fig.axes if a.get_ylabel().startswith("largest tension")]
    assert side == f"largest tension of the cases [N]\n{t_max.min():.6g} to {t_max.max():.6g}"
    assert "envelope over 5 cases" in fig.get_suptitle()


def test_cli_writes_each_state_beside_the_file(mast):
    res = invoke("plot", mast, "--case", "ice")
    assert res.exit_code == 0, res.output
    assert res.output.split() == [str(mast.with_name("mast-ice.png"))]


def test_a_frame_by_time_is_the_nearest_stored_one_and_said(swing, tmp_path):
    res = read_result(swing)
    with h5py.File(swing) as h5:
        times = h5["trajectory/time"][()]
        xs, ts = h5["trajectory/x"][()], h5["trajectory/tension"][()]
        edges = h5["mesh/edges"][()]
        hist_t, hist_r = h5["history/time"][()], h5["history/reaction"][()]
        nodes = h5["history/reaction_nodes"][()]
    k = 12
    asked = float(0.5 * (times[k] + times[k + 1]) - 1e-4)  # nearer frame k
    chosen, shown, note = select(res, time=float(asked))
    assert shown is not None and shown.marker == times[k]
    assert (
        note == f"--time {asked:g} s: drawn at the nearest stored frame, {k} (t = {times[k]:g} s)"
    )
    fig = figure(chosen, shown=shown)
    segments, colours = deformed(fig)
    np.testing.assert_array_equal(segments, xs[k][edges][:, :, [0, 2]])
    np.testing.assert_array_equal(colours, ts[k])
    assert fig.get_suptitle().endswith(f": frame {k}, t = {times[k]:g} s")
    ax = panel(fig, "probe deflection against time")
    marker = next(line for line in ax.get_lines() if line.get_label() == "frame drawn")
    assert list(marker.get_xdata()) == [times[k], times[k]]
    # the reactions of the history's step at that time
    j = int(np.argmin(np.abs(hist_t - times[k])))
    np.testing.assert_array_equal(chosen.reaction[nodes], hist_r[j])
    # by the command line: the note on stderr, the figure RESULT-frameK.png
    out = CliRunner().invoke(main, ["plot", str(swing), "--time", f"{asked!r}"])
    assert out.exit_code == 0, out.output
    assert out.stdout.split() == [str(swing.with_name(f"swing-frame{k}.png"))]
    assert f"drawn at the nearest stored frame, {k}" in out.stderr
    again = invoke("plot", swing, "--frame", -1, "-o", tmp_path / "last.svg")
    assert again.exit_code == 0 and (tmp_path / "last.svg").stat().st_size > 0


@pytest.mark.parametrize(
    ("which", "args", "says"),
    [
        ("mast", ["--case", "wind"], "give one of base, wind_x, wind_y, ice, ULS_wind_x, "),
        ("swing", ["--case", "wind"], "holds no load case or combination"),
        (
            "swing",
            ["--time", "0.5"],
            "beyond the stored frames of swing.h5: they span t = 0 to 0.3 s",
        ),
        ("swing", ["--time", "-1"], "beyond the stored frames"),
        ("swing", ["--time", "nan"], "must be a finite number"),
        ("swing", ["--frame", "31"], "has 31 stored frames: give 0 to 30 (or -31 to -1"),
        ("mast", ["--time", "1"], "is a static run: its 2 frames are load steps"),
        ("mast", ["--case", "ice", "--frame", "1"], "--case and --frame: give one of them"),
        ("mast", ["--history", "--case", "ice"], "--history with --case"),
        ("mast", ["--x", "material.EA"], "plot a sweep's columns: give its directory"),
        ("dir", ["--case", "ice"], "a sweep directory takes --x KEY --y COLUMN"),
    ],
)
def test_what_the_file_lacks_exits_2_with_what_it_has(which, args, says, mast, swing, tmp_path):
    path = {"mast": mast, "swing": swing, "dir": tmp_path}[which]
    res = invoke("plot", path, *args)
    assert res.exit_code == 2, res.output
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("catenet: error: ") and says in lines[0]
