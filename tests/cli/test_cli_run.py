"""``catenet run`` and ``catenet info``: in-process (CliRunner) and as a subprocess, exit
codes, signals, restart, overrides and the files left behind."""

from __future__ import annotations

import os
import re
import resource
import signal
import subprocess
import sys
import tomllib

import h5py
import numpy as np
import pytest
from click.testing import CliRunner
from conftest import (
    catenet_command,
    check_xdmf,
    small_net,
    subprocess_env,
    wait_for_frames,
)

from catenet.case import load_case
from catenet.cli import main
from catenet.output import open_result, read_frame, trajectory_length
from catenet.run.runner import run_case

# A run that takes minutes unless stopped: small steps, little damping.
SLOW = small_net(dt=5e-4, damping=0.1, t_end=100.0, every=5)


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def files_in(directory):
    return sorted(p.name for p in directory.rglob("*") if p.suffix in (".h5", ".xdmf"))


# --------------------------------------------------------------------------------------------
# Success, summary, verbosity, overrides
# --------------------------------------------------------------------------------------------


def test_run_prints_a_summary_and_writes_the_file(tmp_path, write_case):
    case = write_case(small_net(method="static"))
    out = tmp_path / "res" / "static.h5"
    r = invoke("run", case, "-o", out)
    assert r.exit_code == 0, r.output
    for word in ("converged", "yes", "delta", "delta/L", "max tension", "wall time", str(out)):
        assert word in r.stdout
    with h5py.File(out, "r") as h5:
        assert bool(h5["result"].attrs["converged"])
        assert h5.attrs["linear_backend"] in ("pardiso", "scipy")
        delta = h5["result"].attrs["delta"]
    assert f"{delta:.6g}" in r.stdout
    check_xdmf(out.with_suffix(".xdmf"))


def test_quiet_prints_nothing_and_verbose_shows_newton(tmp_path, write_case):
    case = write_case(small_net(method="static"))
    r = invoke("run", case, "-o", tmp_path / "q.h5", "-q")
    assert r.exit_code == 0 and r.stdout == "" and r.stderr == ""
    r = invoke("run", case, "-o", tmp_path / "v.h5", "-v")
    assert r.exit_code == 0
    assert "catenet.solver.newton" in r.stderr  # Newton's iterations at DEBUG


def test_set_overrides_reach_the_run_and_the_file(tmp_path, write_case):
    case = write_case(small_net(method="static"))
    a, b = tmp_path / "a.h5", tmp_path / "b.h5"
    assert invoke("run", case, "-o", a, "-q").exit_code == 0
    r = invoke("run", case, "-o", b, "-q", "--set", "load.pressure=50", "--set", "output.every=0")
    assert r.exit_code == 0, r.output
    with h5py.File(a, "r") as ha, h5py.File(b, "r") as hb:
        assert tomllib.loads(hb.attrs["case"])["load"]["pressure"] == 50.0
        assert "trajectory" not in hb and "trajectory" in ha
        assert 0 < hb["result"].attrs["delta"] < ha["result"].attrs["delta"]
    assert check_xdmf(b.with_suffix(".xdmf"))["grids"] == 1


def test_output_file_from_the_case_and_default_case(tmp_path, write_case, monkeypatch):
    monkeypatch.chdir(tmp_path)
    case = write_case(small_net(method="static"))
    assert invoke("run", case, "-q").exit_code == 0
    assert (tmp_path / "out" / "small.h5").is_file()  # output.file, relative to the cwd
    r = invoke("run", "-q", "--set", "output.every=0", "-o", tmp_path / "default.h5")
    assert r.exit_code == 0, r.output
    with h5py.File(tmp_path / "default.h5", "r") as h5:
        case = tomllib.loads(h5.attrs["case"])
        assert case["geometry"]["n"] == 34 and bool(h5["result"].attrs["converged"])


def test_dynamic_run_trajectory_and_xdmf(tmp_path, write_case):
    case = write_case(small_net(every=7))
    out = tmp_path / "dyn.h5"
    r = invoke("run", case, "-o", out)
    assert r.exit_code == 0, r.output
    with h5py.File(out, "r") as h5:
        t = h5["trajectory/time"][()]
        a = h5["result"].attrs
        assert a["equilibrium"] and a["message"] == "equilibrium"
        assert t[0] == 0.0 and t[-1] == pytest.approx(a["time"])  # the last step is kept
        assert np.all(np.diff(t) > 0)
        np.testing.assert_array_equal(h5["trajectory/x"][-1], h5["result/x"][()])
        np.testing.assert_array_equal(h5["trajectory/v"][-1], h5["result/v"][()])
    found = check_xdmf(out.with_suffix(".xdmf"))
    assert found["times"] == pytest.approx(list(t))


# --------------------------------------------------------------------------------------------
# Bad input: exit 2, nothing written
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "args, message",
    [
        (["--set", "solver.dt=-1"], "solver.dt"),
        (["--set", "solver.bogus=1"], "solver.bogus"),
        (["--set", "no-equals-sign"], "key.path=value"),
        (["--set", "geometry.n=7"], "geometry.n"),
        (["-o", "{tmp}/a_file/out.h5"], "not a directory"),
        (["-o", "{tmp}"], "directory"),
        (["-o", "{tmp}/run.xdmf"], "sidecar"),
        (["-o", "{tmp}/case.toml"], "case file itself"),
        (["--restart", "{tmp}/a_file"], "--restart"),
        (["--set", "solver.method=static", "--restart", "{tmp}/old.h5"], "only dynamic"),
    ],
)
def test_bad_input_exits_2_and_leaves_no_file(tmp_path, write_case, args, message):
    case = write_case(small_net(t_end=0.05))
    (tmp_path / "a_file").write_text("not a result file")
    old = tmp_path / "old.h5"
    assert invoke("run", case, "-o", old, "-q").exit_code == 0
    before = files_in(tmp_path)
    args = [a.replace("{tmp}", str(tmp_path)) for a in args]
    r = invoke("run", case, "-o", tmp_path / "new" / "out.h5", *args)
    assert r.exit_code == 2, r.output
    assert message in r.stderr
    assert "Traceback" not in r.output
    assert files_in(tmp_path) == before
    assert not (tmp_path / "new").exists()


def test_bad_case_file_exits_2(tmp_path, write_case):
    bad = write_case(small_net() + "\n[extra]\nkey = 1\n", "bad.toml")
    r = invoke("run", bad, "-o", tmp_path / "x.h5")
    assert r.exit_code == 2 and "extra" in r.stderr
    r = invoke("run", tmp_path / "missing.toml", "-o", tmp_path / "x.h5")
    assert r.exit_code == 2
    assert files_in(tmp_path) == []


def test_restart_of_another_net_is_refused(tmp_path, write_case):
    case = write_case(small_net(t_end=0.05))
    old = tmp_path / "old.h5"
    assert invoke("run", case, "-o", old, "-q").exit_code == 0
    r = invoke("run", case, "--restart", old, "-o", tmp_path / "n.h5", "--set", "geometry.n=12")
    assert r.exit_code == 2 and "nodes" in r.stderr
    r = invoke("run", case, "--restart", old, "-o", old, "--set", "solver.t_end=1")
    assert r.exit_code == 2 and "also the output file" in r.stderr
    r = invoke("run", case, "--restart", old, "-o", tmp_path / "n.h5")  # old reached t_end
    assert r.exit_code == 2 and "t_end" in r.stderr
    assert not (tmp_path / "n.h5").exists()


# --------------------------------------------------------------------------------------------
# Run-time failures: exit 1, the last good state kept
# --------------------------------------------------------------------------------------------


def test_no_convergence_exits_1_and_keeps_the_state(tmp_path, write_case):
    case = write_case(small_net(method="static"))
    out = tmp_path / "fail.h5"
    r = invoke("run", case, "-o", out, "--set", "solver.max_iter=1", "--set", "solver.steps=2")
    assert r.exit_code == 1, r.output
    assert "catenet: error:" in r.stderr and str(out) in r.stderr
    assert "Traceback" not in r.output
    with h5py.File(out, "r") as h5:
        a = h5["result"].attrs
        assert not a["converged"] and a["message"]
        assert np.all(np.isfinite(h5["result/x"][()]))
    check_xdmf(out.with_suffix(".xdmf"))


def test_full_disk_exits_1_and_names_the_saved_file(tmp_path, write_case):
    case = write_case(small_net(every=1))
    out = tmp_path / "full.h5"

    def limit():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (150_000, 150_000))

    proc = subprocess.run(
        catenet_command("run", case, "-o", out),
        env=subprocess_env(),
        preexec_fn=limit,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 1, proc.stderr
    assert "writing failed" in proc.stderr and "saved to" in proc.stderr
    saved = re.search(r"saved to (\S+) instead", proc.stderr).group(1)
    try:
        with h5py.File(saved, "r") as h5:
            assert bool(h5["result"].attrs["equilibrium"])
    finally:
        os.unlink(saved)


# --------------------------------------------------------------------------------------------
# Signals (subprocess) and restart
# --------------------------------------------------------------------------------------------


def start_slow_run(tmp_path, write_case, name):
    case = write_case(SLOW, "slow.toml")
    out = tmp_path / f"{name}.h5"
    proc = subprocess.Popen(
        catenet_command("run", case, "-o", out),
        env=subprocess_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    wait_for_frames(out, 3, proc)
    return proc, out, case


@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 1)])
def test_sigint_and_sigterm_close_the_file(tmp_path, write_case, sig, code):
    proc, out, case = start_slow_run(tmp_path, write_case, "sig")
    proc.send_signal(sig)
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == code, stderr
    assert "interrupted" in stderr and "Traceback" not in stderr
    with h5py.File(out, "r") as h5:  # closed properly: any HDF5 reader opens it
        a = h5["result"].attrs
        assert not a["converged"] and a["message"] == "interrupted"
        n = trajectory_length(h5)
        assert n >= 3
        assert h5["trajectory/time"][n - 1] == pytest.approx(a["time"])
        np.testing.assert_array_equal(h5["trajectory/x"][n - 1], h5["result/x"][()])
    check_xdmf(out.with_suffix(".xdmf"))
    if sig == signal.SIGINT:
        # ... and the run goes on from where it stopped.
        t_stop = read_frame(out).t
        t_end = t_stop + 0.01
        r = invoke(
            "run",
            case,
            "--restart",
            out,
            "-o",
            tmp_path / "more.h5",
            "-q",
            "--set",
            f"solver.t_end={t_end!r}",
            "--set",
            "solver.dt=5e-3",
        )
        assert r.exit_code == 0, r.output
        with h5py.File(tmp_path / "more.h5", "r") as h5:
            assert h5["trajectory/time"][0] == t_stop
            np.testing.assert_array_equal(h5["trajectory/x"][0], read_frame(out).x)
            assert h5.attrs["restart_from"] == str(out)
            assert h5["result"].attrs["time"] == pytest.approx(t_end)


def test_sigkill_leaves_a_readable_trajectory(tmp_path, write_case):
    proc, out, _ = start_slow_run(tmp_path, write_case, "kill")
    proc.send_signal(signal.SIGKILL)
    proc.communicate(timeout=60)
    assert proc.returncode == -signal.SIGKILL
    with open_result(out) as h5:
        n = trajectory_length(h5)
        assert n >= 3 and "result" not in h5
        x = h5["trajectory/x"][:n]
        assert np.all(np.isfinite(x))
        assert np.all(np.diff(h5["trajectory/time"][:n]) > 0)


def test_restart_equals_the_uninterrupted_run(tmp_path, write_case):
    """Stopping after 40 steps and going on from the stored frame (positions, velocities,
    time) follows the same steps as the uninterrupted run: the same equilibrium."""
    case = load_case(write_case(small_net(every=1)))
    full = run_case(case, tmp_path / "full.h5")
    assert full.equilibrium

    count = {"n": 0}

    def stop():
        count["n"] += 1
        return count["n"] >= 40

    part = run_case(case, tmp_path / "part.h5", stop=stop)
    assert not part.converged and part.message == "interrupted" and part.steps == 40
    rest = run_case(case, tmp_path / "rest.h5", restart=tmp_path / "part.h5")
    assert rest.equilibrium and rest.converged
    np.testing.assert_allclose(rest.x, full.x, rtol=0, atol=1e-8)
    assert rest.time == pytest.approx(full.time)
    assert part.steps + rest.steps == full.steps


# --------------------------------------------------------------------------------------------
# The entry points and catenet info
# --------------------------------------------------------------------------------------------


def test_python_m_catenet_and_help(tmp_path, write_case):
    proc = subprocess.run(
        catenet_command("--help"), capture_output=True, text=True, env=subprocess_env(), timeout=120
    )
    assert proc.returncode == 0 and "run" in proc.stdout
    case = write_case(small_net(method="static"))
    proc = subprocess.run(
        catenet_command("run", case, "-o", tmp_path / "m.h5"),
        capture_output=True,
        text=True,
        env=subprocess_env(),
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert "converged" in proc.stdout


IMPORTS = """
import sys
from catenet.cli import main
try:
    main(sys.argv[1:])
except SystemExit as exc:
    code = exc.code or 0
heavy = ("numpy", "numba", "scipy", "h5py", "catenet.study", "benchmarks", "catenet.sweep")
print("IMPORTED", *sorted(m for m in heavy if m in sys.modules))
sys.exit(code)
"""


def imported_by(*args) -> list[str]:
    """The heavy modules a catenet command imports (run in a fresh interpreter)."""
    proc = subprocess.run(
        [sys.executable, "-c", IMPORTS, *map(str, args)],
        capture_output=True,
        text=True,
        env=subprocess_env(),
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    line = [ln for ln in proc.stdout.splitlines() if ln.startswith("IMPORTED")][-1]
    return line.split()[1:]


def test_version_is_looked_up_when_asked():
    from importlib.metadata import version

    r = invoke("--version")
    assert r.exit_code == 0, r.output
    assert r.output == f"catenet, version {version('catenet')}\n"


def test_help_imports_no_numpy_and_run_no_studies(tmp_path, write_case):
    assert imported_by("--help") == []
    assert imported_by("run", "--help") == []
    case = write_case(small_net(method="static"))
    modules = imported_by("run", case, "-o", tmp_path / "r.h5", "-q")
    assert "numpy" in modules and "catenet.study" not in modules and "benchmarks" not in modules
    assert "catenet.sweep" not in modules


LEAN = """
import sys
from catenet.cli import main
try:
    main(sys.argv[1:])
except SystemExit as exc:
    assert not exc.code, exc.code
from numba.np.ufunc import parallel
optional = ("catenet.terms.strands", "catenet.kernels.strands", "catenet.terms.rigid",
            "catenet.terms.body", "catenet.kernels.body", "catenet.terms.contact",
            "catenet.terms.bending", "catenet.kernels.bending")
print("LOADED", *sorted(m for m in optional if m in sys.modules))
print("POOL", parallel._is_initialized)
import atexit, gc
atexit._run_exitfuncs()  # what the interpreter runs at exit, before its last collection
print("FROZEN", gc.get_freeze_count() > 0, gc.isenabled())
"""


def test_a_plain_static_run_loads_only_what_it_uses(tmp_path, write_case):
    """No self-contact, bodies, obstacles or rods: their terms and kernels stay unloaded, and
    Numba's thread pool (catenet's kernels are serial) is not started."""
    case = write_case(small_net(method="static"))
    proc = subprocess.run(
        [sys.executable, "-c", LEAN, "run", str(case), "-o", str(tmp_path / "r.h5"), "-q"],
        capture_output=True,
        text=True,
        env=subprocess_env(),
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    lines = dict(ln.split(" ", 1) if " " in ln else (ln, "") for ln in proc.stdout.splitlines())
    assert lines["LOADED"] == ""
    assert lines["POOL"] == "False"
    # At exit every object is frozen: the last collection does not walk Numba's objects;
    # the collector itself is on again after the imports.
    assert lines["FROZEN"] == "True True"


def test_collecting_later_restores_the_collector():
    import gc

    from catenet.cli.common import collecting_later

    assert gc.isenabled()
    with pytest.raises(RuntimeError), collecting_later():
        assert not gc.isenabled()
        raise RuntimeError("an import that fails")
    assert gc.isenabled()
    gc.disable()
    try:
        with collecting_later():
            pass
        assert not gc.isenabled()  # left as it was
    finally:
        gc.enable()


def test_set_numba_threads_starts_the_pool_set_threads_only_where_it_runs():
    code = (
        "import numba\n"
        "from numba.np.ufunc import parallel\n"
        "from catenet.solver.threads import set_numba_threads, set_threads\n"
        "set_threads(1)\n"
        "print(parallel._is_initialized)\n"
        "set_numba_threads(1)\n"
        "print(parallel._is_initialized, numba.get_num_threads())\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=subprocess_env()
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["False", "True", "1"]


def test_info():
    r = invoke("info")
    assert r.exit_code == 0, r.output
    for word in (
        "catenet",
        "numpy",
        "scipy",
        "numba",
        "h5py",
        "click",
        "pypardiso",
        "mkl",
        "linear backend",
        "mkl threads",
        "numba threads",
        "numba cache",
    ):
        assert word in r.stdout


def fake_dynamic(fail_at: int, nan: bool):
    """A solve_dynamic that takes ``fail_at`` steps of 0.01 s, then fails: with a
    ConvergenceError, or by producing a NaN state."""
    from catenet.errors import ConvergenceError

    def solve(net, loads, *, x0, v0, t0, on_step, dt, **kw):
        x, v = x0.copy(), np.full_like(x0, 0.5)
        for step in range(1, fail_at + 1):
            x = x.copy()
            x[~net.fixed, 2] -= 1e-3
            if on_step(step, t0 + step * dt, x, v):
                raise AssertionError("not stopped here")
        if nan:
            x = x.copy()
            x[~net.fixed, 2] = np.nan
            on_step(fail_at + 1, t0 + (fail_at + 1) * dt, x, v)
        raise ConvergenceError("dynamic step failed", iterations=9, history=[1.0], state=x)

    return solve


@pytest.mark.parametrize("nan", [False, True], ids=["no-convergence", "non-finite"])
def test_dynamic_failure_keeps_the_last_good_step(tmp_path, write_case, monkeypatch, nan):
    import catenet.solver.dynamic

    monkeypatch.setattr(catenet.solver.dynamic, "solve_dynamic", fake_dynamic(4, nan))
    case = write_case(small_net(every=3))
    out = tmp_path / "fail.h5"
    r = invoke("run", case, "-o", out)
    assert r.exit_code == 1, r.output
    assert ("non-finite" if nan else "dynamic step failed") in r.stderr
    assert str(out) in r.stderr and "Traceback" not in r.output
    with h5py.File(out, "r") as h5:
        a = h5["result"].attrs
        assert not a["converged"] and a["steps"] == 4 and a["time"] == pytest.approx(0.04)
        t = h5["trajectory/time"][()]
        np.testing.assert_allclose(t, [0.0, 0.03, 0.04])  # every 3rd step, and the last good
        x = h5["result/x"][()]
        assert np.all(np.isfinite(h5["trajectory/x"][()])) and np.all(np.isfinite(x))
        np.testing.assert_array_equal(h5["trajectory/x"][-1], x)
        free = ~h5["mesh/fixed"][()]
        np.testing.assert_allclose(x[free, 2], -4e-3)
    check_xdmf(out.with_suffix(".xdmf"))


@pytest.mark.parametrize("start, noted", [("equilibrium", True), ("given", False)])
def test_displacements_of_a_run_from_its_equilibrium_say_their_reference(tmp_path, start, noted):
    """A cable drawn straight and hung at rest by ``initial_state = "equilibrium"``: its
    displacements (contract: from the given geometry) are mostly its sag at t = 0, which
    the summary says, not a motion of the run."""
    case = tmp_path / "hung.toml"
    case.write_text(
        '[geometry]\nkind = "cable"\nstart = [0, 0, 0]\nend = [10, 0, 0]\nnodes = 11\n'
        "[material]\nE = 1e9\nradius = 0.01\ndensity = 1000.0\nprestress = 100.0\n"
        "[load]\ngravity = [0, 0, -9.81]\n"
        f'[solver]\nmethod = "dynamic"\ninitial_state = "{start}"\nt_end = 0.05\n'
    )
    r = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "h.h5")])
    assert r.exit_code == 0, r.output
    line = next(x for x in r.output.splitlines() if x.startswith("max displ."))
    assert (
        "(from the given geometry: the run starts from its static equilibrium)" in line
    ) is noted
