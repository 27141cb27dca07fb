"""What the figures show: the paper's axes and closed forms for its single-cable cases,
a colour range that follows the data, the undeformed net above the grid, a deformation
scale, a readable palette for the sweep figures. The figures are inspected as matplotlib
objects (labels, lines, limits), the way a reader would check them."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import CONFIGS

from catenet.case import load_case
from catenet.output import read_result
from catenet.plot.figure import figure, paper_curve, plot_result
from catenet.run.runner import run_case
from catenet.validate import analytic


def run(tmp_path, name, *overrides):
    case = load_case(CONFIGS / f"{name}.toml", overrides)
    out = tmp_path / f"{name}.h5"
    run_case(case, out)
    return read_result(out)


@pytest.fixture
def example_result(example):
    """``example_result(name)``: the example's result file read (run once per session)."""
    return lambda name: read_result(example(name))


def panel(fig, title_start):
    return next(ax for ax in fig.axes if ax.get_title().startswith(title_start))


@pytest.mark.parametrize(
    "name, xlabel, closed",
    [
        ("catenary", "end shortening ΔL/L [-]", "Eq. 15 (inextensible catenary)"),
        ("midpoint_load", "load F/EA [-]", "Eq. 17"),
    ],
)
def test_paper_cases_draw_the_papers_axes_and_closed_form(example_result, name, xlabel, closed):
    res = example_result(name)
    curve = paper_curve(res)
    assert curve is not None
    fig = figure(res)
    ax = panel(fig, "paper Fig. 2")
    assert ax.get_xlabel() == xlabel and ax.get_ylabel().endswith("/L [-]")
    labels = [line.get_label() for line in ax.get_lines()]
    assert closed in labels and "catenet (load steps)" in labels
    # catenet's points lie on the closed form (the paper's Figs. 2e-2f)
    closed_y = np.interp(curve.x, curve.x_closed, curve.y_closed)
    tol = (
        0.02 if name == "catenary" else 1e-4
    )  # Eq. 15 is inextensible (W/EA = 1e-3); Eq. 17 linearly interpolated
    np.testing.assert_allclose(curve.y, closed_y, rtol=tol)
    if name == "catenary":
        assert curve.x[-1] == pytest.approx(0.2)
        assert curve.y_closed[-1] == pytest.approx(analytic.catenary_sag(1.0, 0.2))
    side = panel(fig, "side view")
    assert any(line.get_label().startswith(("Eq. 14", "Eq. 16")) for line in side.get_lines())


def test_other_cases_keep_the_load_factor_axis(tmp_path):
    res = run(
        tmp_path,
        "catenary",
        "load.gravity=[0, 0, -9.81]",
        "supports.move.1.displacement=[-0.05, 0, 0]",
    )
    assert paper_curve(res) is None  # not symmetric: not the paper's case
    ax = panel(figure(res), "probe deflection")
    assert ax.get_xlabel() == "load factor [-]"


def colorbar(fig):
    return next(ax for ax in fig.axes if ax.get_label() == "<colorbar>")


def test_the_colour_range_follows_the_data(tmp_path, example_result):
    """A prestressed net under a small load: tensions of about 25 kN vary by little; the
    colour bar spans their range, not 0 to the maximum."""
    res = run(
        tmp_path,
        "fig4a_n10_alpha_0",
        "material.prestress=25000.0",
        "material.E=1e11",
        "load.pressure=3000.0",
        "geometry.edge_length=0.05",
    )
    lo, hi = colorbar(figure(res)).get_ylim()
    assert lo == pytest.approx(res.tension.min()) and hi == pytest.approx(res.tension.max())
    assert lo > 20_000
    uniform = example_result("midpoint_load")  # every edge carries the same tension
    lo, hi = colorbar(figure(uniform)).get_ylim()
    assert lo < uniform.tension.min() <= uniform.tension.max() < hi


def test_the_undeformed_net_is_drawn_above_the_grid_and_scaled_deformation(tmp_path):
    res = run(tmp_path, "fig4a_n10_alpha_0", "geometry.edge_length=0.05")
    fig = figure(res, scale=10.0)
    side = panel(fig, "side view")
    assert side.get_axisbelow() is True
    undeformed = next(c for c in side.collections if c.get_label() == "undeformed")
    deformed = next(c for c in side.collections if c.get_label() == "deformed")
    assert undeformed.get_zorder() > 0.5  # above the grid lines
    z = np.concatenate([seg[:, 1] for seg in deformed.get_segments()])
    assert z.min() == pytest.approx(-10.0 * res.delta, rel=0.05)
    assert "displacements × 10" in fig._suptitle.get_text()
    flat = figure(res)  # true scale: the net is flat, so its z axis is stretched
    ax3 = next(ax for ax in flat.axes if ax.name == "3d")
    assert "stretched" in ax3.get_zlabel()
    with pytest.raises(Exception, match="--scale"):
        figure(res, scale=0.0)


def test_plot_command_takes_a_scale(tmp_path, example_result):
    from click.testing import CliRunner

    from catenet.cli import main

    res = example_result("midpoint_load")
    out = tmp_path / "m.png"
    r = CliRunner().invoke(main, ["plot", str(res.path), "-o", str(out), "--scale", "2"])
    assert r.exit_code == 0, r.output and out.exists()
    assert plot_result(res.path, tmp_path / "n.svg").exists()


def test_sweep_figure_curves_differ_in_colour_marker_and_line():
    from catenet.study.figures import COLOURS, style

    styles = [style(k) for k in range(6)]
    for a, b in zip(styles, styles[1:], strict=False):
        assert a["color"] != b["color"] and a["marker"] != b["marker"] and a["ls"] != b["ls"]
    assert "#F0E442" not in COLOURS  # no yellow on white
