"""What a run tells besides its result (issue 12, items 3-5 of the run path): warnings
about degrees taken as radians, strains beyond the material law's range, solver keys the
method ignores and large trajectories (each with a case that triggers it and one that does
not); the dynamic progress toward rest; stagnation and interruption inside Newton; exact
frame times; an unwritable output path."""

from __future__ import annotations

import dataclasses
import logging
import math
import tomllib

import h5py
import numpy as np
import pytest
from click.testing import CliRunner
from conftest import small_net

from catenet.case import load_case, parse_case
from catenet.case.kinds import warn
from catenet.cli import main
from catenet.run import advice
from catenet.run.runner import run_case

# The static case without the dynamic keys (set explicitly, they would be warned about).
STATIC = "\n".join(
    line
    for line in small_net(method="static").splitlines()
    if not line.startswith(("dt =", "damping =", "t_end ="))
)
DYNAMIC = small_net(method="dynamic", dt=0.01, t_end=5.0)


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.fixture(autouse=True)
def fresh_warnings():
    """Case-loading warnings are given once per process: forget the earlier ones."""
    warn._WARNED.clear()
    yield
    warn._WARNED.clear()


def case_of(write_case, text=STATIC, *sets):
    return load_case(write_case(text), sets)


def messages(caplog, level=logging.WARNING):
    return [r.getMessage() for r in caplog.records if r.levelno >= level]


# ------------------------------------------------------------------------------- angles


def test_an_angle_in_degrees_is_warned_about(write_case, caplog):
    with caplog.at_level(logging.WARNING):
        case_of(write_case, STATIC, "geometry.alpha=45")
    (msg,) = [m for m in messages(caplog) if "geometry.alpha" in m]
    assert "looks like degrees" in msg and "0.785398" in msg and "outside [0, 2 pi]" in msg


@pytest.mark.parametrize("alpha", [-1.0, 400.0])
def test_an_angle_outside_0_2pi_is_warned_about(write_case, caplog, alpha):
    with caplog.at_level(logging.WARNING):
        case_of(write_case, STATIC, f"geometry.alpha={alpha!r}")
    (msg,) = [m for m in messages(caplog) if "geometry.alpha" in m]
    assert "outside [0, 2 pi]" in msg
    assert ("looks like degrees" in msg) == (abs(alpha) <= 360)


@pytest.mark.parametrize("alpha", [0.0, math.pi / 4, 2 * math.pi])
def test_an_angle_in_radians_is_not_warned_about(write_case, caplog, alpha):
    with caplog.at_level(logging.WARNING):
        case_of(write_case, STATIC, f"geometry.alpha={alpha!r}")
    assert not [m for m in messages(caplog) if "geometry.alpha" in m]


def test_a_sweep_warns_about_the_angle_once(write_case, caplog):
    data = {
        "geometry": {"kind": "square_net", "n": 4, "alpha": 30.0, "size": 1.0},
        "material": {"EA": 1.0},
    }
    data["geometry"]["edge_length"] = 0.5
    with caplog.at_level(logging.WARNING):
        for _ in range(3):
            parse_case(data)
    assert len([m for m in messages(caplog) if "geometry.alpha" in m]) == 1


def test_the_cli_shows_the_angle_warning_on_stderr(tmp_path, write_case):
    r = invoke(
        "run", write_case(STATIC), "-q", "-o", tmp_path / "a.h5", "--set", "geometry.alpha=30"
    )
    assert r.exit_code == 0, r.output
    assert not r.stderr  # -q shows errors only
    warn._WARNED.clear()
    r = invoke("run", write_case(STATIC), "-o", tmp_path / "a.h5", "--set", "geometry.alpha=30")
    assert r.exit_code == 0, r.output
    assert "catenet: warning:" in r.stderr and "looks like degrees" in r.stderr


# ------------------------------------------------------------------------------ strains


def test_strain_beyond_the_linear_law_is_warned_about(tmp_path, write_case, caplog):
    case = case_of(write_case, STATIC, "load.pressure=1e4", "solver.steps=3")
    with caplog.at_level(logging.WARNING):
        result = run_case(case, tmp_path / "big.h5")
    assert result.converged and 0.05 < result.max_strain < 0.5  # within 10x its range
    (msg,) = [m for m in messages(caplog) if "material law's range" in m]
    assert "linear law (meant for strains <= 0.05)" in msg and "neo_hookean" in msg
    assert result.report.strain_warning == msg and not result.report.implausible
    r = invoke("run", write_case(STATIC), "-o", tmp_path / "c.h5", "--set", "load.pressure=1e4")
    assert r.exit_code == 0
    assert "beyond the material law's range" in r.stdout and "catenet: warning:" in r.stderr


def test_a_strain_no_cable_reaches_fails_the_run(tmp_path, write_case, caplog):
    """Strains beyond 10x the law's range (a unit slip: E in MPa, loads in N/mm^2): the
    equations were solved, the model is not what the user meant. The run fails (exit 1,
    also with -q), its summary says "converged no", /result keeps the state marked
    failed, and no load case is solved from it."""
    import h5py

    case = case_of(write_case, STATIC, "load.pressure=1e9", "solver.steps=3")
    with caplog.at_level(logging.WARNING):
        result = run_case(case, tmp_path / "big.h5")
    assert not result.converged and result.max_strain > 1e3
    assert result.report.implausible.startswith("implausible (check units and supports)")
    assert "linear law (meant for strains <= 0.05)" in result.report.implausible
    assert not [m for m in messages(caplog) if m.startswith("strain")]  # said once: the error
    with h5py.File(tmp_path / "big.h5") as h5:
        attrs = h5["result"].attrs
        assert not attrs["converged"] and attrs["outcome"] == "failed"
        assert attrs["message"] == result.report.implausible
    for quiet in ([], ["-q"]):
        r = invoke("run", write_case(STATIC), "-o", tmp_path / "c.h5", "--set",
                   "load.pressure=1e9", *quiet)  # fmt: skip
        assert r.exit_code == 1, r.output
        assert "catenet: error: the result is implausible" in r.stderr
        assert ("converged    no (implausible" in r.stdout) is not bool(quiet)


def test_small_strain_is_not_warned_about(tmp_path, write_case, caplog):
    case = case_of(write_case, STATIC)
    with caplog.at_level(logging.WARNING):
        result = run_case(case, tmp_path / "small.h5")
    assert 0 < result.max_strain < 0.05
    assert not messages(caplog) and result.report.strain_warning == ""


def test_each_law_has_its_own_range():
    from catenet.model.laws import Law, table_rows
    from catenet.model.net import Net

    nodes = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0]])

    def net(law=None):
        return Net.from_arrays(nodes, [[0, 1], [1, 2]], EA=1.0, fixed=[0, 2], law=law)

    x = nodes * 1.5  # both edges at strain 0.5
    msg = advice.strain_beyond_law(net(), x)
    assert "2 of 2 edges of the linear law (meant for strains <= 0.05)" in msg
    assert advice.strain_beyond_law(net(), nodes * 1.04) is None
    assert advice.strain_beyond_law(net(Law.uniform(2, "hencky")), x) is None  # up to 1.0
    assert advice.strain_beyond_law(net(Law.uniform(2, "hencky")), nodes * 2.5) is not None
    assert advice.strain_beyond_law(net(Law.uniform(2, "neo_hookean")), nodes * 50) is None
    rows, _ = table_rows([[0.1, 10.0]])
    msg = advice.strain_beyond_law(net(Law.uniform(2, "table", table=rows)), x)
    assert "table law (meant for strains <= 0.1)" in msg and "material.table" in msg


# --------------------------------------------------------------------- solver keys


@pytest.mark.parametrize(
    "method, sets, keys",
    [
        ("dynamic", ["solver.steps=4"], ["solver.steps = 4"]),
        ("dynamic", ["solver.max_iter=30"], []),  # a time step's budget: read
        (
            "static",
            ["solver.dt=0.5", "solver.t_end=3.0"],
            ["solver.dt = 0.5", "solver.t_end = 3.0"],
        ),
        ("static", ["solver.damping=2.0"], ["solver.damping = 2.0"]),
        ("dynamic", ["solver.dt=0.02", "solver.t_end=2.0"], []),
        ("static", ["solver.steps=3", "solver.max_iter=50"], []),
        ("static", ["solver.dt=0.01"], []),  # the default: nothing to say
    ],
)
def test_solver_keys_the_method_ignores(write_case, method, sets, keys):
    case = case_of(write_case, STATIC, f"solver.method={method!r}", *sets)
    found = advice.ignored_solver_keys(case.solver)
    assert [m.split(":")[0] for m in found] == keys
    assert all("ignored with solver.method" in m for m in found)


def test_ignored_keys_are_warned_before_the_run(tmp_path, write_case):
    r = invoke("run", write_case(DYNAMIC), "-o", tmp_path / "d.h5", "--set", "solver.steps=4")
    assert r.exit_code == 0, r.output
    assert "solver.steps = 4: ignored with solver.method = 'dynamic'" in r.stderr
    r = invoke("run", write_case(DYNAMIC), "-o", tmp_path / "e.h5")
    assert r.exit_code == 0 and "warning:" not in r.stderr


# ------------------------------------------------------------------------- trajectory


def test_trajectory_estimate_bounds_the_file(tmp_path, write_case):
    case = case_of(write_case, small_net(t_end=0.5, every=2))
    result = run_case(case, tmp_path / "t.h5")
    from catenet.case import build

    est = advice.trajectory(case, build(case).net)
    with h5py.File(tmp_path / "t.h5") as h5:
        g = h5["trajectory"]
        frames = len(g["time"])
        stored = sum(g[k][:frames].nbytes for k in ("x", "v", "tension", "time"))
    assert est.frames == 1 + math.ceil(50 / 2) == frames  # t_end / dt / every, + frame 0
    assert est.bytes == stored
    assert result.report.trajectory_bytes == est.bytes
    static = case_of(write_case, STATIC, "solver.steps=7", "output.every=3")
    assert advice.trajectory(static, build(static).net).frames == 3  # 3, 6 and 7
    # newmark files keep the scheme's accelerations too
    newmark = case_of(write_case, small_net(t_end=0.1, every=2), "solver.integrator=newmark")
    run_case(newmark, tmp_path / "n.h5")
    est = advice.trajectory(newmark, build(newmark).net)
    with h5py.File(tmp_path / "n.h5") as h5:
        g = h5["trajectory"]
        frames = len(g["time"])
        stored = sum(g[k][:frames].nbytes for k in ("x", "v", "a", "tension", "time"))
    assert est.bytes == stored
    none = case_of(write_case, STATIC, "output.every=0")
    assert advice.trajectory(none, build(none).net) is None


def test_a_large_trajectory_is_warned_about(tmp_path, write_case, caplog, monkeypatch):
    case = case_of(write_case, small_net(t_end=0.2))
    with caplog.at_level(logging.WARNING):
        run_case(case, tmp_path / "a.h5")
    # 21 frames of 12.4 KiB: no word on them (the one warning: this damped transient's
    # implicit Euler steps took half its energy, catenet.run.integrator_advice)
    (own,) = messages(caplog)
    assert "removed 54% of the run's largest energy on its own" in own
    caplog.clear()
    monkeypatch.setattr(advice, "WARN_BYTES", 100_000)
    monkeypatch.setattr(advice, "TARGET_BYTES", 100_000)
    with caplog.at_level(logging.WARNING):
        run_case(case, tmp_path / "b.h5")
    (msg,) = [m for m in messages(caplog) if "on its own" not in m]
    assert "the trajectory will take up to" in msg and "21 frames" in msg
    assert "set output.every = 5 " in msg and "output.every = 0" in msg  # 261 KiB / 5


def test_the_summary_names_a_large_trajectory(tmp_path, write_case, monkeypatch):
    case = write_case(small_net(t_end=0.2))
    r = invoke("run", case, "-o", tmp_path / "a.h5")
    assert "estimated" not in r.stdout
    monkeypatch.setattr(advice, "LARGE_BYTES", 1000)
    r = invoke("run", case, "-o", tmp_path / "b.h5")
    (line,) = [x for x in r.stdout.splitlines() if x.startswith("output")]
    assert "written" in line and "estimated before the run" in line


def test_suggested_every_is_round():
    t = advice.Trajectory(frames=10_001, frame=400_000, every=1)
    k = t.suggestion()
    assert k in (20, 50) and t.bytes / k <= 2 * advice.TARGET_BYTES
    assert advice.format_bytes(1536) == "1.5 KiB" and advice.format_bytes(12) == "12 bytes"


# ---------------------------------------------------------------------------- progress


def test_dynamic_progress_goes_toward_rest_not_t_end(tmp_path, write_case):
    from catenet.cli.run import Relaxation

    case = case_of(write_case, small_net(t_end=100.0))
    seen = []
    result = run_case(case, tmp_path / "p.h5", progress=lambda d, t, rest: seen.append(rest))
    assert result.equilibrium and result.time < 10.0  # far from t_end = 100 s
    assert seen[-1] <= 1.0 < max(seen)
    relax = Relaxation()
    fracs = [relax.update(0.0, r)[0] for r in (1e4, 1e2, 1.0)]
    assert fracs == [0.0, 0.5, 1.0]
    assert relax.update(0.0, float("nan")) == (0.0, "t = 0 s (supports moving)")


def test_progress_without_eta(capsys):
    import io

    from catenet.cli.common import Progress

    stream = io.StringIO()
    bar = Progress("rest", enabled=True, stream=stream)
    bar.update(0.5, 1.0, note="t = 1 s", eta=False)
    assert "ETA" not in stream.getvalue() and "50.0%" in stream.getvalue()
    bar = Progress("load", enabled=True, stream=stream)
    bar.update(0.5, 1.0)
    assert "ETA" in stream.getvalue()


# ------------------------------------------------------------------ Newton: stop, stall


def test_newton_stops_when_it_stagnates(monkeypatch):
    """A residual held by noise a few times the round-off floor above the solution (as
    the sums of a very large net are): Newton stops STAGNATION iterations after it gets
    there, not at max_iter; noise within every DOF's own floor is converged; the same
    problem without the noise converges."""
    from catenet.kernels.sparse import norm
    from catenet.solver import newton

    pot, x = _potential()
    ref = newton.solve_newton(pot, x.copy(), rtol=1e-8, max_iter=200)
    assert ref.converged and ref.reason == "converged"  # the usual case: no stagnation
    real = pot.evaluate
    rng = np.random.default_rng(0)

    size = {"noise": 0.5}

    def noisy(x):
        ev = real(x)
        noise = rng.standard_normal(ev.g.shape)
        g = ev.g + noise * (size["noise"] * ev.floor / np.linalg.norm(noise))
        return dataclasses.replace(ev, g=g, gnorm=float(norm(g)))

    monkeypatch.setattr(pot, "evaluate", noisy)
    monkeypatch.setattr(newton, "STALL_FLOOR", 0.0)  # its stop at the floor switched off
    # Noise within every DOF's own round-off floor (Potential.at_floor): converged there,
    # never "stagnated".
    r = newton.solve_newton(pot, x.copy(), rtol=1e-30, max_iter=200, atol=0.0)
    assert r.converged and r.reason == "converged (round-off floor)", r.reason
    # Noise a few times the round-off floor above the solution: stagnated, and soon.
    size["noise"] = 3.0
    r = newton.solve_newton(pot, x.copy(), rtol=1e-30, max_iter=200, atol=0.0)
    assert not r.converged and r.reason.startswith("stagnated"), r.reason
    assert r.iterations <= ref.iterations + 2 * newton.STAGNATION < 200
    assert "round-off floor" in r.reason


def _potential():
    """The n = 6 square net under a downward force at every free node, from flat."""
    from catenet.model.builders import Material, square_net
    from catenet.model.net import Loads
    from catenet.solver.static import Workspace

    sq = square_net(6, 0.0, 1.0, 0.1, Material(EA=3141.6))
    force = np.zeros((sq.net.n_nodes, 3))
    force[~sq.net.fixed, 2] = -1.0
    ws = Workspace(sq.net)
    return ws.potential(Loads(force=force)), sq.net.nodes.copy()


def test_a_stop_request_ends_newton_between_iterations(tmp_path, write_case):
    """A static run of one load step sees no step end before its equilibrium: only the
    check inside Newton can stop it."""
    case = case_of(write_case, STATIC)
    calls = []

    def stop():
        calls.append(1)
        return len(calls) >= 3

    result = run_case(case, tmp_path / "s.h5", interrupt=stop)
    assert not result.converged and result.message == "interrupted"
    assert result.steps == 0
    with h5py.File(tmp_path / "s.h5") as h5:
        assert h5["result"].attrs["message"] == "interrupted"
        assert not h5["result"].attrs["converged"]
    dyn = case_of(write_case, DYNAMIC)
    calls.clear()
    result = run_case(dyn, tmp_path / "d.h5", interrupt=stop)
    assert result.message == "interrupted" and result.steps <= 2
    with h5py.File(tmp_path / "d.h5") as h5:
        assert h5["result"].attrs["message"] == "interrupted"


def test_no_stop_request_no_interruption(tmp_path, write_case):
    result = run_case(case_of(write_case, STATIC), tmp_path / "n.h5", interrupt=lambda: False)
    assert result.converged and result.message == "equilibrium"


# -------------------------------------------------------------------------- frame times


def test_frame_times_are_whole_steps(tmp_path, write_case):
    case = case_of(write_case, small_net(dt=0.001, t_end=1.5, every=1))
    run_case(case, tmp_path / "t.h5")
    with h5py.File(tmp_path / "t.h5") as h5:
        t = h5["trajectory/time"][:]
    k = np.arange(len(t))
    assert np.array_equal(t, k * 0.001)  # t = k h with one rounding, no accumulated error
    assert t[1437] == 1.437


def test_times_after_step_cuts_are_exact():
    from catenet.solver.dynamic import MAX_CUTS, _advance

    dt = 0.01
    q = dt / 2**MAX_CUTS
    t = 0.0
    for h in [dt] * 7 + [dt / 2] * 4 + [dt / 4] * 3 + [dt] * 100:
        t = _advance(t, h, 0.0, 10.0, q)
    steps = 7 + 2 + 0.75 + 100
    assert t == round(steps * 2**MAX_CUTS) * q == pytest.approx(steps * dt, rel=1e-15)
    assert _advance(9.99, 0.01, 0.0, 10.0, q) == 10.0
    assert _advance(9.995, 10.0 - 9.995, 0.0, 10.0, q) == 10.0


# ------------------------------------------------------------------ unwritable output


@pytest.mark.parametrize("where", ["/proc/catenet-test.h5", "/sys/catenet-test.h5"])
def test_an_unwritable_path_is_one_sentence_and_exit_2(tmp_path, write_case, where):
    r = invoke("run", write_case(STATIC), "-o", where)
    assert r.exit_code == 2, r.output
    (line,) = r.stderr.strip().splitlines()
    assert line.startswith(f"catenet: error: output file '{where}': cannot be written")
    assert "errno" not in line and "o_flags" not in line and "synchronously" not in line


def test_a_read_only_directory_is_found_before_computing(tmp_path, write_case, monkeypatch):
    import catenet.case

    built = []
    monkeypatch.setattr(catenet.case, "build", lambda case: built.append(case))
    ro = tmp_path / "ro"
    ro.mkdir()

    def refuse(*args, **kwargs):
        raise PermissionError(13, "Read-only file system")

    monkeypatch.setattr("tempfile.TemporaryFile", refuse)
    from catenet.errors import ConfigError

    with pytest.raises(ConfigError, match="Read-only file system"):
        run_case(case_of(write_case, STATIC), ro / "sub" / "x.h5")
    assert not built and not (ro / "sub").exists()


def test_sigterm_stops_a_single_long_newton_solve(tmp_path, write_case):
    """One static load step of a 27 000-node net: SIGTERM sent once Newton has logged its
    first iteration stops it at the next iteration (no step ends before the equilibrium,
    so only the check inside Newton can), and the file says "interrupted"."""
    import signal
    import subprocess

    from conftest import catenet_command, subprocess_env

    case = write_case(STATIC.replace("edge_length = 0.05", "edge_length = 0.002"))
    out = tmp_path / "big.h5"
    proc = subprocess.Popen(
        catenet_command("run", case, "-o", out, "-v"),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=subprocess_env(),
    )
    seen = []
    for line in proc.stderr:
        seen.append(line)
        if "|r| =" in line:
            proc.send_signal(signal.SIGTERM)
            break
    stdout, stderr = proc.communicate(timeout=300)
    assert proc.returncode == 1, "".join(seen) + stderr
    assert "catenet: interrupted at load factor 0" in stderr
    with h5py.File(out) as h5:
        a = h5["result"].attrs
        assert a["message"] == "interrupted" and not a["converged"]


# --- warnings in the case's units -------------------------------------------------------

MM_NET = """units = "N-mm"

[geometry]
kind = "square_net"
n = 6
alpha = 0.0
size = 1000.0
edge_length = 200.0

[material]
E = 2e5
radius = 2.0
density = 7.85e-9

[load]
gravity = [0.0, 0.0, -9810.0]

[[obstacle]]
kind = "sphere"
center = [10.0, 10.0, -60.0]
radius = 20.0

[solver]
method = "static"
"""


def test_a_warning_names_lengths_in_the_case_units_on_the_terminal_and_in_the_file(tmp_path):
    """A 40 mm sphere under a net of 125 mm edges in an N-mm case: the warning that it
    is narrower than the edges read "40 m across" and "125 m" before (the solver's SI
    names); now mm, on the terminal and in /result's warnings alike."""
    case = tmp_path / "mm.toml"
    case.write_text(MM_NET)
    out = tmp_path / "mm.h5"
    done = invoke("run", case, "-o", out)
    assert done.exit_code == 0, done.output
    said = " ".join(done.output.split())
    assert "(sphere, 40 mm across) is narrower than the net's edges (125 mm," in said, said
    with h5py.File(out) as f:
        kept = str(f["/result"].attrs["warnings"])
    assert "40 mm across" in kept and "(125 mm, the median)" in kept, kept
    assert " m across" not in said + kept


def test_a_thrown_net_without_damping_given_flies_undamped(caplog):
    """A net given a velocity by [[mass]] and no solver.damping: its motion is the answer,
    so solver.damping defaults to 0 and its free flight keeps its speed (the paper's
    1 1/s left e^-t of it, 0.14 at 2 s, and the run said so); damping given is kept; a
    net thrown nowhere (nothing depends on time) keeps the paper's 1 1/s. Nothing is
    said about damping in any of them."""
    from catenet.case.kinds import warn as warned

    base = small_net(method="dynamic", dt=0.01, t_end=2.0)
    base = "\n".join(line for line in base.splitlines() if not line.startswith("damping ="))
    thrown = base + '\n[[mass]]\nnode = "center"\nvelocity = [0.0, 0.0, 2.0]\n'
    dampings = []
    for text in (thrown, thrown.replace("[solver]", "[solver]\ndamping = 0.5"), base):
        warned._WARNED.clear()
        caplog.clear()
        with caplog.at_level(logging.WARNING, logger="catenet"):
            dampings.append(parse_case(tomllib.loads(text)).solver.damping)
        assert not [r for r in caplog.records if "damp" in r.getMessage()]
    assert dampings == [0.0, 0.5, 1.0]
