"""`catenet run` of dynamic relaxation to rest (solver.t_end = "rest"): the summary of an
undamped run without t_end, the exit 1 of a run that cannot rest, and a run that spent
its steps, restarted to rest and plotted from frames at uneven times."""

from __future__ import annotations

import h5py
import numpy as np
from click.testing import CliRunner
from conftest import check_xdmf, small_net

from catenet.cli import main


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def without_t_end(text: str) -> str:
    lines = [ln for ln in text.splitlines() if not ln.startswith("t_end")]
    assert len(lines) == len(text.splitlines()) - 1
    return "\n".join(lines) + "\n"


def test_an_undamped_case_without_t_end_runs_10_s_and_says_why_it_never_rests(tmp_path, write_case):
    # Newmark with rho_inf = 1 damps nothing: the net swings for ever. (On this
    # tension-only net at dt = 0.05 s it also gains energy at the slack-taut kink, which a
    # run refuses by default: tests/solver/test_energy.py; here the check is off.)
    case = write_case(without_t_end(small_net(dt=0.05, damping=0.0)))
    out = tmp_path / "undamped.h5"
    r = invoke(
        "run",
        case,
        "-o",
        out,
        "--set",
        "solver.integrator=newmark",
        "--set",
        "solver.rho_inf=1",
        "--set",
        "output.every=0",
        "--set",
        "solver.energy_tolerance=1e9",
    )
    assert r.exit_code == 0, r.output
    assert (
        "not yet at equilibrium: a transient (solver.damping = 0): its motion to solver.t_end "
        "is the answer; undamped, it never rests" in r.stdout
    )
    with h5py.File(out, "r") as h5:
        assert h5["result"].attrs["time"] == 10.0 and not h5["result"].attrs["equilibrium"]


def test_rest_without_damping_exits_1_with_the_reason(tmp_path, write_case):
    case = write_case(small_net(damping=0.0).replace("t_end = 5.0", 't_end = "rest"'))
    r = invoke("run", case, "-o", tmp_path / "no.h5")
    assert r.exit_code == 1, r.output
    assert "an undamped run never rests: give solver.t_end or damping" in r.stderr
    assert "Traceback" not in r.output


def test_a_run_out_of_steps_exits_1_and_its_restart_goes_on_to_rest(tmp_path, write_case):
    case = write_case(without_t_end(small_net()))
    first, second = tmp_path / "first.h5", tmp_path / "second.h5"
    r = invoke("run", case, "-o", first, "--set", "solver.max_steps=4")
    assert r.exit_code == 1, r.output
    assert "not at rest after solver.max_steps = 4 time steps" in r.stderr
    with h5py.File(first, "r") as h5:
        assert not h5["result"].attrs["converged"]
        assert len(h5["trajectory/time"]) == 5  # the start and 4 steps
    r = invoke("run", case, "--restart", first, "-o", second)
    assert r.exit_code == 0, r.output
    assert "equilibrium" in r.stdout
    with h5py.File(second, "r") as h5:
        t = h5["trajectory/time"][()]
        assert bool(h5["result"].attrs["equilibrium"])
    steps = np.diff(t)
    assert np.all(steps > 0) and steps.max() > 2 * steps.min()  # pseudo-time: uneven
    check_xdmf(second.with_suffix(".xdmf"))
    r = invoke("plot", second, "-o", tmp_path / "second.png")
    assert r.exit_code == 0, r.output
    assert (tmp_path / "second.png").stat().st_size > 0


def test_the_peaks_of_a_run_to_rest_are_dated_in_its_pseudo_time(tmp_path):
    """A hanging wire relaxed to rest from its straight start: the way down overshoots (the
    peak tension is far above the final one), but that path is the relaxation's pseudo-time,
    not a physical transient: the summary says so, and the final state is the static one."""
    case = tmp_path / "wire.toml"
    case.write_text(
        '[geometry]\nkind = "cable"\nstart = [0, 0, 0]\nend = [80, 0, 10]\nlength = 84\n'
        "nodes = 41\n[material]\nE = 160e9\nradius = 0.012\ndensity = 7850\n"
        '[load]\ngravity = [0, 0, -9.81]\n[solver]\nmethod = "dynamic"\n'
    )
    rest = invoke("run", case, "-o", tmp_path / "rest.h5")
    assert rest.exit_code == 0, rest.output
    assert "pseudo-time t = " in rest.stdout and "not a physical transient" in rest.stdout
    static = invoke("run", case, "-o", tmp_path / "static.h5", "--set", "solver.method=static")
    assert static.exit_code == 0, static.output
    with h5py.File(tmp_path / "rest.h5") as a, h5py.File(tmp_path / "static.h5") as b:
        ta, tb = a["result/tension"][()], b["result/tension"][()]
        assert np.max(np.abs(ta - tb)) < 1e-6 * np.max(tb)
        assert a["result/peak_tension"][()].max() > 1.5 * ta.max()  # the way down overshot
    from catenet.output.reader import read_result

    assert read_result(tmp_path / "rest.h5").to_rest  # the figure's time axis: pseudo-time
    assert not read_result(tmp_path / "static.h5").to_rest
