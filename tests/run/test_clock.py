"""Start-up against solve time: what ``catenet run`` reports and imports, and the clock
that splits them (``catenet.run.clock``)."""

from __future__ import annotations


def test_catenet_run_reports_solve_and_startup_time_apart(write_case, tmp_path):
    """catenet run prints the solve time and the start-up time (imports, case, JIT cache)
    and stores them in /result; together they fit in the process's wall time, and the
    run imports neither pypardiso, scipy.sparse nor the studies."""
    import subprocess
    import sys
    import time

    import h5py
    from conftest import small_net, subprocess_env

    case = write_case(small_net(method="static"))
    out = tmp_path / "small.h5"
    code = (
        "import sys, runpy\n"
        "sys.argv = ['catenet', 'run', sys.argv[1], '-o', sys.argv[2]]\n"
        "try:\n"
        "    runpy.run_module('catenet', run_name='__main__')\n"
        "except SystemExit as exc:\n"
        "    heavy = sorted({m.split('.')[0] + ('.sparse' if m.startswith('scipy.sparse')"
        " else '') for m in sys.modules if m.startswith(('pypardiso', 'scipy.sparse',"
        " 'catenet.study', 'benchmarks'))})\n"
        "    print('heavy:', heavy)\n"
        "    raise\n"
    )
    start = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-c", code, str(case), str(out)],
        capture_output=True,
        text=True,
        env=subprocess_env(),
    )
    wall = time.perf_counter() - start
    assert proc.returncode == 0, proc.stderr
    assert "heavy: []" in proc.stdout
    line = next(ln for ln in proc.stdout.splitlines() if ln.startswith("wall time"))
    assert "solve" in line and "start-up" in line and "JIT cache" in line
    with h5py.File(out, "r") as fh:
        a = fh["result"].attrs
        solve, startup = float(a["solve_time"]), float(a["startup_time"])
    assert 0 < solve and 0 < startup and solve + startup < wall


def test_clock_moves_jit_time_to_startup():
    """A kernel compiled inside the solve counts as start-up; writing is left out of the
    solve; without a solve block everything so far is start-up."""
    import numba

    from catenet.run.clock import Clock, since_process_start

    clock = Clock()
    assert clock.solve == 0.0 and clock.startup > 0.0

    @numba.njit
    def fresh(a):  # a new function: compiled on its first call
        return a + 1.0

    with clock.solving():
        assert fresh(1.0) == 2.0
        with clock.aside():
            sum(range(10_000))
    assert clock.jit > 0.0
    assert clock.startup >= clock.jit
    assert clock.solve < clock.jit  # the compile is not solving
    assert clock.startup <= since_process_start()


def test_an_equilibrium_start_counts_as_solve_time(write_case, tmp_path, monkeypatch):
    """A dynamic run from its equilibrium (``solver.initial_state = "equilibrium"``) counts
    that static solve in the solve time: a newcomer's rope lifted by a bar spent 110 s
    there while the summary gave solve 3.84 s and start-up 2.13 s of a 117 s run. Here
    the start is made to take 1 s longer."""
    import time

    import h5py
    from click.testing import CliRunner
    from conftest import small_net

    from catenet.cli import main
    from catenet.solver import path

    slow = path.equilibrium_start

    def slower(*args, **kwargs):
        time.sleep(1.0)
        return slow(*args, **kwargs)

    monkeypatch.setattr(path, "equilibrium_start", slower)
    text = small_net(method="dynamic", t_end=0.02, dt=0.01)
    case = write_case(text.replace("[solver]", '[solver]\ninitial_state = "equilibrium"'))
    out = tmp_path / "start.h5"
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(out)])
    assert done.exit_code == 0, done.output
    with h5py.File(out, "r") as fh:
        assert float(fh["result"].attrs["solve_time"]) >= 1.0
