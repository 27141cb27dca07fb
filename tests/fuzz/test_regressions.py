"""Regression tests built from the cases a hostile fuzz of catenet found (each failure as
it showed): hangs on truncated files, a false "converged", non-finite results, tracebacks,
messages that blamed the wrong key, exit 1 for bad input, leftovers, runaway work."""

from __future__ import annotations

import math
import os
import re
import subprocess
import warnings
from pathlib import Path

import h5py
import numpy as np
import pytest
from conftest import catenet_command, small_net, subprocess_env
from fuzzing import HIDDEN, NUMPY_REPR, invoke, judge

pytestmark = pytest.mark.filterwarnings("ignore")

SMALL = small_net(t_end=0.3).replace("edge_length = 0.05", "edge_length = 0.1")


def run(tmp_path, *args, case=SMALL, name="case.toml"):
    path = tmp_path / name
    path.write_text(case)
    result = invoke(["run", path, *args], seconds=120, cwd=tmp_path)
    return result, result.output + (result.stderr or "")


def hidden(root: Path) -> list[str]:
    return [p.name for p in root.rglob("*") if HIDDEN.match(p.name)]


@pytest.fixture(scope="module")
def dynamic_file(tmp_path_factory):
    work = tmp_path_factory.mktemp("dyn")
    (work / "case.toml").write_text(small_net(t_end=1.0))
    out = work / "d.h5"
    result = invoke(["run", work / "case.toml", "-o", out, "-q"], seconds=120)
    assert result.exit_code == 0, result.output
    return work / "case.toml", out


# --- hangs on truncated result files ----------------------------------------------------------


@pytest.mark.parametrize("fraction", [96, 512, 77703, 0.6])
def test_truncated_result_files_fail_fast(dynamic_file, tmp_path, fraction):
    """A dynamic run's file cut at 96, 512, 77 703 bytes (and at 60 %): --restart, plot,
    export and repair each end at once with exit 2 (SWMR reading retried for ever)."""
    case, src = dynamic_file
    raw = src.read_bytes()
    cut = tmp_path / "cut.h5"
    cut.write_bytes(raw[: int(fraction * len(raw)) if fraction < 1 else fraction])
    commands = [
        ["run", case, "--restart", cut, "-o", tmp_path / "again.h5", "--set", "solver.t_end=2"],
        ["plot", cut, "-o", tmp_path / "fig.png"],
        ["export", cut, "--to", "vtu", "-o", tmp_path / "ex"],
        ["repair", cut],
    ]
    for args in commands:  # a fresh interpreter: a hang inside HDF5 holds the GIL
        proc = subprocess.run(
            catenet_command(*args), capture_output=True, text=True, env=subprocess_env(), timeout=60
        )
        assert proc.returncode == 2, (args, proc.stderr)
        assert "Traceback" not in proc.stderr and "catenet: error:" in proc.stderr
    assert not (tmp_path / "again.h5").exists() and not hidden(tmp_path)


# --- a false "converged" and non-finite results -------------------------------------------------


@pytest.mark.parametrize(
    "sets, key",
    [
        (["material.E=1e300"], "material.E = 1e300"),
        (["load.pressure=1e300"], "load.pressure = 1e300"),
        (["solver.damping=1e300"], "solver.damping = 1e300"),
        (["material.radius=1e200"], "material.radius = 1e200"),
        (["material.E=1e90", "material.radius=1e90"], "material.E = 1e90, material.radius = 1e90"),
        (["solver.steps=1e300", "solver.method=static"], "solver.steps = 1e300"),
        (["solver.dt=1e-300"], "solver.dt = 1e-300"),
        (["load.gravity=[0, 0, -1e300]"], "load.gravity = [0, 0, -1e300]"),
        (["material.E=1e-320"], "material.E = 1e-320, material.radius = 0.01: EA = 4.94e-324"),
    ],
)
def test_numbers_beyond_the_arithmetic_name_their_key(tmp_path, sets, key):
    args = ["-o", tmp_path / "o.h5", "-q"]
    for s in sets:
        args += ["--set", s]
    result, text = run(tmp_path, *args)
    assert result.exit_code == 2, text
    assert key in text and not NUMPY_REPR.search(text)
    assert not (tmp_path / "o.h5").exists()


def test_never_converged_against_a_non_finite_tolerance(tmp_path, monkeypatch):
    """E = 1e300 with the range checks out of the way: the run may fail (exit 1) but never
    says "converged" (it did, with 0 Newton iterations and a residual of 3 N)."""
    from catenet.case import guard, keys

    monkeypatch.setattr(keys, "MAGNITUDE", math.inf)
    monkeypatch.setattr("catenet.model.net.MAGNITUDE", math.inf)
    for name in ("guard_scales", "guard_material"):
        monkeypatch.setattr(guard, name, lambda *a: None)
        monkeypatch.setattr(f"catenet.case.scene.{name}", lambda *a: None)
    result, text = run(tmp_path, "-o", tmp_path / "o.h5", "--set", "material.E=1e300")
    assert result.exit_code == 1, text
    assert "converged after" not in text and "non-finite" in text
    with h5py.File(tmp_path / "o.h5") as h5:
        assert not h5["result"].attrs["converged"]
        assert np.all(np.isfinite(h5["result/x"][()]))


def test_newton_refuses_a_non_finite_scale():
    from catenet.solver import newton
    from catenet.solver.potential import Evaluation

    class Potential:  # the load scale overflowed
        def evaluate(self, x):
            g = np.full(3, 1.0)
            return Evaluation(0.0, g, math.inf, 0.0, 0.0, float(np.linalg.norm(g)))

        system = type("S", (), {"free_dofs": np.arange(3)})()

    result = newton.solve_newton(Potential(), np.zeros((1, 3)), rtol=1e-8, max_iter=5)
    assert not result.converged and "non-finite tolerance" in result.reason


# --- tracebacks -----------------------------------------------------------------------------


def test_sweep_values_beyond_the_arithmetic(tmp_path):
    case = tmp_path / "case.toml"
    case.write_text(small_net(method="static"))
    for value in ("10**400", "0:1:inf", "9**9**9", "0:1e-300:1", "1e308*10"):
        result = invoke(["sweep", case, "-o", tmp_path / "sw", "-p", f"load.pressure={value}"])
        text = result.output
        assert result.exit_code == 2 and "--param" in text, (value, text)
        assert "Traceback" not in text
    assert not (tmp_path / "sw").exists()


def test_a_date_in_a_sweep_is_named_as_written(tmp_path):
    case = tmp_path / "case.toml"
    case.write_text(small_net(method="static") + "\n[sweep]\nload.pressure = [2020-01-01]\n")
    result = invoke(["sweep", case, "-o", tmp_path / "sw"])
    assert result.exit_code == 2
    assert "sweep.load.pressure: 2020-01-01: dates" in result.output
    assert "datetime" not in result.output


def test_deep_nesting_in_a_case_and_in_set(tmp_path):
    deep = SMALL + "\n[extra]\n" + "a." * 3000 + "b = 1\n"
    result, text = run(tmp_path, "-o", tmp_path / "o.h5", "--set", "title=x", case=deep)
    assert result.exit_code == 2 and "nested more than" in text, text
    result, text = run(tmp_path, "-o", tmp_path / "o.h5", "--set", "title." + "a." * 1200 + "b=1")
    assert result.exit_code == 2 and "key path of 1202 parts" in text, text


def test_undecodable_paths(tmp_path):
    """An output path with bytes that are not UTF-8: exit 2, nothing written (a traceback
    in the XDMF writer); a case file with such a name runs."""
    bad = os.fsdecode(b"bad\xff.h5")
    result, text = run(tmp_path, "-o", tmp_path / bad, "-q")
    assert result.exit_code == 2 and "not UTF-8" in text, text
    assert list(tmp_path.iterdir()) == [tmp_path / "case.toml"]
    result, text = run(tmp_path, "-o", tmp_path / "ok.h5", "-q", name=os.fsdecode(b"c\xff.toml"))
    assert result.exit_code == 0, text
    with h5py.File(tmp_path / "ok.h5") as h5:
        assert h5.attrs["source"].endswith("c\\xff.toml")  # the byte, escaped


def test_restart_files_of_the_wrong_shape_or_another_case(dynamic_file, tmp_path):
    case, src = dynamic_file
    bad = tmp_path / "bad.h5"
    bad.write_bytes(src.read_bytes())
    with h5py.File(bad, "a") as h5:
        del h5["trajectory/x"]
        h5["trajectory/x"] = np.zeros((3, 5, 3))
    base = ["run", case, "-o", tmp_path / "again.h5", "--set", "solver.t_end=2", "--restart"]
    result = invoke([*base, bad])
    assert result.exit_code == 2 and "shape (5, 3)" in result.output, result.output
    result = invoke([*base, src, "--set", "material.E=2e7"])
    assert result.exit_code == 2 and "EA differ" in result.output, result.output
    result = invoke([*base, src, "--set", "geometry.edge_length=0.1"])
    assert result.exit_code == 2 and "its net has" in result.output, result.output
    assert not (tmp_path / "again.h5").exists()


# --- messages that blamed the wrong key -------------------------------------------------------


GRAPH = """
title = "graph"
[geometry]
kind = "graph"
nodes = [[0, 0, 0], [1, 0, -0.1], [2, 0, 0]]
edges = [[0, 1], [1, 2]]
fixed = [0, 2]
[material]
EA = 1000.0
[load]
point = [{node = 1, force = [0, 0, -10]}]
[solver]
method = "static"
"""


def test_a_huge_coordinate_is_blamed_on_the_node(tmp_path):
    result, text = run(
        tmp_path, "-o", tmp_path / "o.h5", "--set", "geometry.nodes=[[0,0,0],[1e300,0,0],[2,0,0]]",
        case=GRAPH,
    )  # fmt: skip
    assert result.exit_code == 2 and "geometry.nodes[1] = [1e300, 0, 0]" in text, text
    assert "rest_length" not in text and not NUMPY_REPR.search(text)
    result, text = run(tmp_path, "-o", tmp_path / "o.h5", "--set", "geometry.size=1e300")
    assert result.exit_code == 2 and "geometry.size = 1e300" in text, text


def test_the_square_net_builder_raises_no_warning():
    """Hostile sizes in the Python API: a ConfigError, not an overflow warning first."""
    import catenet as cn

    mat = cn.Material.from_E(10e6, radius=0.01, density=1000.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for size, edge in ((1e300, 1e300), (1e300, 1.8e308), (1e101, 1.0)):
            with pytest.raises(cn.ConfigError, match="geometry"):
                cn.square_net(2, 0.3, size, edge, mat)
        with pytest.raises(cn.ConfigError, match="huge coordinates"):
            cn.Net.from_arrays([[0, 0, 0], [1e300, 0, 0]], [[0, 1]], EA=1.0, fixed=[0])


# --- exit 1 for bad input, leftovers, runaway work -----------------------------------------------


def test_names_too_long_and_directories_below_files_are_bad_input(tmp_path):
    for length in (300, 240):  # 240: the file fits, its hidden spare's copy does not
        result, text = run(tmp_path, "-o", tmp_path / ("x" * length + ".h5"))
        assert result.exit_code == 2 and "too long for the file system" in text, text
    (tmp_path / "afile").write_text("")
    case = tmp_path / "case.toml"
    result = invoke(["sweep", case, "-o", tmp_path / "afile" / "sub", "-p", "load.pressure=1"])
    assert result.exit_code == 2 and "is not a directory" in result.output, result.output
    result = invoke(["sweep", case, "-o", tmp_path / ("y" * 300), "-p", "load.pressure=1"])
    assert result.exit_code == 2 and "too long" in result.output, result.output


def test_a_sidecar_path_that_is_a_directory_leaves_nothing(tmp_path):
    (tmp_path / "r.xdmf").mkdir()
    result, text = run(tmp_path, "-o", tmp_path / "r.h5", "-q")
    assert result.exit_code == 2 and "sidecar" in text, text
    assert sorted(p.name for p in tmp_path.iterdir()) == ["case.toml", "r.xdmf"]


def test_a_garbage_scheduler_address_is_refused_at_once(tmp_path):
    case = tmp_path / "case.toml"
    case.write_text(small_net(method="static"))
    for address, code in (("garbage!!", 2), ("tcp://127.0.0.1:1", 1), ("host:99999", 2)):
        result = invoke(
            ["sweep", case, "-o", tmp_path / "sw", "-p", "load.pressure=1", "--scheduler", address],
            seconds=30,
        )
        assert result.exit_code == code and "--scheduler" in result.output, result.output
        assert "Traceback" not in result.output
    assert not (tmp_path / "sw").exists()


def test_a_mesh_file_meshio_exits_on_is_bad_input(tmp_path):
    """meshio prints a line and calls sys.exit for some broken STL files."""
    (tmp_path / "cube.stl").write_text("solid\nfacet normal 0 0 -1\n outer loop\n  vertex -1 -1\n")
    case = SMALL + '\n[[obstacle]]\nkind = "mesh"\nfile = "cube.stl"\n'
    result, text = run(tmp_path, "-o", tmp_path / "o.h5", case=case)
    assert result.exit_code == 2 and "obstacle[0].file = 'cube.stl': meshio cannot read" in text
    assert judge(result, tmp_path).good


def test_bad_input_found_once_the_file_is_open_leaves_nothing(tmp_path):
    """A density so small that the masses underflow to 0 is found by the dynamic solver,
    after the file got its first frame: exit 2 and no file (one was left)."""
    from fuzzing import CONFIGS

    case = (CONFIGS / "contact" / "ball_off_box.toml").read_text()
    result, text = run(
        tmp_path, "-o", tmp_path / "o.h5", "--set", "material.density=5e-324",
        "--set", "solver.t_end=0.2", case=case,
    )  # fmt: skip
    assert result.exit_code == 2 and "material.density" in text, text
    assert sorted(p.name for p in tmp_path.iterdir()) == ["case.toml"]


@pytest.mark.parametrize("name", ["sphere_catch.toml", "net_on_sphere.toml"])
def test_a_denormal_barrier_distance_is_named(tmp_path, name):
    """obstacle.distance = 5e-324 made the barrier's stiffness infinite: a ValueError
    from the ball's term (the long fuzz run found it)."""
    from fuzzing import CONFIGS

    case = (CONFIGS / "contact" / name).read_text()
    result, text = run(
        tmp_path, "-o", tmp_path / "o.h5", "--set", "obstacle.0.distance=5e-324",
        "--set", "solver.t_end=0.1", case=case,
    )  # fmt: skip
    assert result.exit_code == 2, text
    assert "obstacle[0].distance = 5e-324: the barrier's stiffness would be inf" in text


def test_a_solid_whose_extent_round_off_loses(tmp_path):
    """The box of ball_off_box.toml moved to x = 2^63 (the suite's fuzz found it): its
    outline's extent was lost to round-off there, the edges' watch built a barrier of
    zero reach, and the run ended with an internal error. That solid is now left
    unwatched, and the run ends as any other."""
    from fuzzing import CONFIGS

    case = (CONFIGS / "contact" / "ball_off_box.toml").read_text()
    result, text = run(
        tmp_path, "-o", tmp_path / "o.h5", "--set", "obstacle.0.center.0=9223372036854775807",
        "--set", "solver.t_end=0.05", case=case,
    )  # fmt: skip
    assert judge(result, tmp_path).good, text
    assert "internal error" not in text


def test_a_far_node_of_a_cable_graph(tmp_path):
    """A mooring line's fairlead moved to x = 1e99 (the quick tier found it): the cable
    split into 2e99 edges was cast to int64 garbage and built; now the size guard refuses
    it. A dynamic run that fails keeps a finite /result residual (it stored inf)."""
    import tomllib

    import tomli_w
    from fuzzing import CONFIGS, small

    data = small(tomllib.loads((CONFIGS / "friction" / "mooring_pulled.toml").read_text()))
    data["geometry"]["nodes"][1][0] = 1e99
    result, text = run(tmp_path, "-o", tmp_path / "o.h5", case=tomli_w.dumps(data))
    assert result.exit_code == 2 and "the net would have about 4e+99 nodes" in text, text
    result, text = run(
        tmp_path, "-o", tmp_path / "o.h5", "--set", "solver.max_iter=1",
        "--set", "solver.rtol=1e-300", case=SMALL,
    )  # fmt: skip
    if result.exit_code == 1:
        with h5py.File(tmp_path / "o.h5") as h5:
            assert math.isfinite(h5["result"].attrs["residual"])
    assert judge(result, tmp_path).good


@pytest.mark.parametrize(
    "name, value",
    [
        ("mesh/fixed", np.array([b"not", b"numbers"])),
        ("mesh/EA", np.float64(np.nan)),
        ("mesh/rest_length", np.array([b"not", b"numbers"])),
        ("mesh/nodes", np.zeros((104, 2, 2))),
        ("trajectory/tension", None),
    ],
)
def test_export_of_datasets_of_the_wrong_type_or_shape(dynamic_file, tmp_path, name, value):
    """Damaged result files the long fuzz run gave `catenet export`: exit 2 naming the
    file (they were internal errors: TypeError, ValueError, KeyError)."""
    _, src = dynamic_file
    bad = tmp_path / "bad.h5"
    bad.write_bytes(src.read_bytes())
    with h5py.File(bad, "a") as h5:
        del h5[name]
        if value is not None:
            h5[name] = value
    result = invoke(["export", bad, "--to", "vtu", "-o", tmp_path / "ex"], cwd=tmp_path)
    assert result.exit_code == 2 and "bad.h5" in result.output, result.output
    assert judge(result, tmp_path, {bad}).good


def test_a_vanishing_friction_slip_is_named(tmp_path):
    """obstacle.slip = 1e-300 (the quick tier found it): the friction's gradient overflowed
    at the start and the failed run stored an infinite residual."""
    import tomllib

    import tomli_w
    from fuzzing import CONFIGS, small

    data = small(tomllib.loads((CONFIGS / "friction" / "mooring_pulled.toml").read_text()))
    data["obstacle"][0]["slip"] = 1e-300
    result, text = run(tmp_path, "-o", tmp_path / "o.h5", case=tomli_w.dumps(data))
    assert result.exit_code == 2 and "obstacle[0].slip = 1e-300: must be at least" in text, text
    assert sorted(p.name for p in tmp_path.iterdir()) == ["case.toml"]


def test_steps_that_stay_short_end_the_run(tmp_path):
    """The tether net with material.E = 2**63 - 1 (1e8 times Dyneema's): every few steps
    one fails and the steps stay about 100x shorter than dt, so that the 1.2 s run would
    take an hour. The run's tries are bounded: exit 1 naming how far it came, what it
    planned and what to change, the last good state kept."""
    from fuzzing import CONFIGS

    for name in ("tether_capture.toml", "tether_capture.json"):
        (tmp_path / name).write_bytes((CONFIGS / "contact" / name).read_bytes())
    out = tmp_path / "o.h5"
    result = invoke(
        ["run", tmp_path / "tether_capture.toml", "-o", out, "--set", "solver.t_end=0.05",
         "--set", "material.E=9223372036854775807"], seconds=120, cwd=tmp_path,
    )  # fmt: skip
    text = result.output + (result.stderr or "")
    assert result.exit_code == 1, text
    assert "dynamic run stopped at t = " in text and "solver.t_end = 0.05 s" in text, text
    assert "where solver.dt = 0.005 s plans 10" in text and "smaller solver.dt" in text, text
    with h5py.File(out) as h5:
        assert not h5["result"].attrs["converged"]
        assert 0 < float(h5["result"].attrs["time"]) < 0.05
    assert judge(result, tmp_path, {out}).good


def test_sets_of_a_graph_too_large_to_split(tmp_path):
    """A hypar roof's node moved to y = 1e99 (the long run found it): its cable split into
    2e99 edges was built to evaluate the case's sets before the size guard and failed
    with "array is too big"; now the size guard names it, exit 2."""
    import tomllib

    import tomli_w
    from fuzzing import CONFIGS, small

    data = small(tomllib.loads((CONFIGS / "structures" / "hypar_roof.toml").read_text()))
    data["geometry"]["nodes"][34][1] = 1e99
    result, text = run(tmp_path, "-o", tmp_path / "o.h5", case=tomli_w.dumps(data))
    assert result.exit_code == 2 and "the net would have about 2e+99 nodes" in text, text
    assert judge(result, tmp_path).good


@pytest.mark.slow
def test_a_body_thrown_too_fast_ends_the_run(tmp_path):
    """The Envisat capture (short) with a corner mass thrown at 9e18 m/s (the long run
    found it): every try failed but a few, each of 25 Newton iterations on the satellite's
    mesh, and the run went on for minutes within its budget of tries. Its failed tries
    are bounded too: exit 1, the last good state kept."""
    import tomllib

    import tomli_w
    from fuzzing import CONFIGS, small

    data = small(tomllib.loads((CONFIGS / "contact" / "envisat_capture.toml").read_text()))
    (tmp_path / "envisat_capture.json").write_bytes(
        (CONFIGS / "contact" / "envisat_capture.json").read_bytes()
    )
    data["mass"][4]["velocity"][0] = 9223372036854775807
    result, text = run(tmp_path, "-o", tmp_path / "o.h5", case=tomli_w.dumps(data))
    assert result.exit_code == 1 and "dynamic run stopped at t = " in text, text
    assert "(40 failed) where solver.dt = 0.01 s plans 30" in text, text  # 30 // 2 + 24 + 1
    with h5py.File(tmp_path / "o.h5") as h5:
        assert not h5["result"].attrs["converged"]
    assert judge(result, tmp_path, {tmp_path / "o.h5"}).good


def _spun_capture(tmp_path, spin: float) -> str:
    """The Envisat capture, small and 0.05 s long, its box spun at ``spin`` rad/s about x."""
    import tomllib

    import tomli_w
    from fuzzing import CONFIGS, small

    data = small(tomllib.loads((CONFIGS / "contact" / "envisat_capture.toml").read_text()))
    (tmp_path / "envisat_capture.json").write_bytes(
        (CONFIGS / "contact" / "envisat_capture.json").read_bytes()
    )
    data["solver"]["t_end"] = 0.05
    data["obstacle"][0]["angular_velocity"][0] = spin
    return tomli_w.dumps(data)


def test_a_body_spun_beyond_the_arithmetic_is_bad_input(tmp_path):
    """The quick tier found the Envisat capture with ``angular_velocity = [1e99, ...]``
    ending in an internal IndexError (an infinite contact force in the summary). A spin
    whose kinetic energy the arithmetic cannot carry is bad input naming the key."""
    case = _spun_capture(tmp_path, 1e99)
    result, text = run(tmp_path, "-o", tmp_path / "huge.h5", case=case)
    assert result.exit_code == 2, text
    assert "obstacle[0].angular_velocity = [1e+99" in text or "[1e99" in text, text
    assert "kinetic energy of spin" in text and "Traceback" not in text, text
    assert judge(result, tmp_path).good


def _box_gaps(path) -> np.ndarray:
    """(frames + 1, nodes) every net node's distance to the box (10 x 4 x 4 m) at its
    pose in every frame of the file and in /result, from the written centre and rotation
    alone (negative inside): the box's own check, not the barrier's."""
    half = np.array([5.0, 2.0, 2.0])
    with h5py.File(path) as h5:
        axes = h5["mesh/obstacles/0/axes"][()]
        frames = [
            (h5["trajectory/x"][k], h5["trajectory/obstacles/0/center"][k],
             h5["trajectory/obstacles/0/rotation"][k])
            for k in range(len(h5["trajectory/time"]))
        ]  # fmt: skip
        frames.append(
            (h5["result/x"][()], h5["result/obstacles/0/center"][()],
             h5["result/obstacles/0/rotation"][()])
        )  # fmt: skip
    gaps = []
    for x, c, R in frames:
        q = (x[:-4] - c) @ R @ axes  # the net's nodes in the box's axes (the body's 4 last)
        out = np.abs(q) - half
        gaps.append(np.where(out.max(axis=1) > 0, np.linalg.norm(np.maximum(out, 0), axis=1),
                             out.max(axis=1)))  # fmt: skip
    return np.array(gaps)


@pytest.mark.parametrize("spin", [1e3, 1e5, 1e7, 1e10])
def test_a_body_spun_far_beyond_its_step_never_has_a_node_on_it(tmp_path, spin):
    """The long fuzz run found the Envisat capture with its box spun at 1e10 rad/s failing
    (exit 1, fine) with a kept state that had a net node on the box: the line search had
    closed in on the step cap iteration after iteration (the barrier cannot hold a node
    off a body whose inertia dwarfs every contact force) until a node sat on the surface
    within round-off, its residual written as inf. Now a step comes no nearer the body
    than the contact's floor and turns it by at most TURN_MAX: at 1e3 to 1e10 rad/s the
    run ends with exit 0 or with catenet's own exit-1 message, and every frame and the
    kept state have every node outside the box and finite numbers (the residual too)."""
    from catenet.terms.rigid_contact import FLOOR_SHARE

    out = tmp_path / "fast.h5"
    result, text = run(tmp_path, "-o", out, case=_spun_capture(tmp_path, spin))
    assert result.exit_code in (0, 1) and "internal error" not in text, text
    if result.exit_code == 1:
        ours = ("dynamic run stopped at t = ", "failed even with h", "the round-off of its forces")
        assert any(m in text for m in ours), text
        assert "the last good state is in" in text, text
    assert judge(result, tmp_path, set()).good, judge(result, tmp_path, set())
    with h5py.File(out) as h5:
        assert math.isfinite(h5["result"].attrs["residual"])
    gaps = _box_gaps(out)
    # Outside by the floor (0.02 m distance: 2e-8 m), less the rotation's round-off.
    assert gaps.min() > 0.5 * FLOOR_SHARE * 0.02, gaps.min()


# --- a long run on a busy machine is no hang ---------------------------------------------------


def test_the_time_limit_counts_processor_time_and_the_clock_only_for_waiting():
    """The long run's seed 11 took the folded net's 10 s run (``solver.t_end`` removed: its
    default) for a hang: 120 s on the clock, 41 s of processor time on a machine at a load
    of 7 on 2 cores. A command is a hang after ``seconds`` of processor time (computing
    for ever) or WALL_FACTOR times that on the clock (waiting for ever)."""
    import time

    import fuzzing
    from fuzzing import Hang, time_limit

    assert fuzzing.WALL_FACTOR == 4.0
    with time_limit(0.3):  # waiting longer than the limit, not as long as the backstop
        time.sleep(0.6)
    start = time.perf_counter()
    with pytest.raises(Hang, match="after 1.2 s on the clock"), time_limit(0.3):
        time.sleep(10.0)
    assert 1.2 <= time.perf_counter() - start < 5.0
    # Computing: 0.3 s of processor time, however long the clock takes to give them
    # (the backstop set far off, so that a busy machine cannot trip it first).
    start = time.process_time()
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(fuzzing, "WALL_FACTOR", 1e3)
        with pytest.raises(Hang, match="after 0.3 s of processor time"), time_limit(0.3):
            while time.process_time() - start < 10.0:
                pass
    assert 0.25 <= time.process_time() - start < 2.0  # the timer counts in scheduler ticks


def test_a_run_still_taking_steps_at_its_checkpoint_is_long_and_a_stuck_one_a_hang(tmp_path):
    """The suite's seed of tether_capture.toml with solver.t_end removed (its default 10 s:
    minutes of a capture) once ran past the 60 s limit and was called a hang. A run that
    has taken a time step within the last quarter of its checkpoint is long, not hung, and
    is stopped there; a command computing without taking steps goes on to its limit and is
    a hang. The run here is given 1000 s, which no machine ends within the limit (a fast
    one ended the 10 s capture in it), and its kernels are compiled first by a run of a few
    steps (on a clean checkout, compiling filled the checkpoint's last quarter)."""
    import time
    import tomllib

    import fuzzing
    import tomli_w
    from fuzzing import CONFIGS, Hang, Long, copy_beside, small, time_limit

    source = CONFIGS / "contact" / "tether_capture.toml"
    copy_beside(source, tmp_path)
    data = small(tomllib.loads(source.read_text()))
    data["solver"]["t_end"] = 0.02
    (tmp_path / "case.toml").write_text(tomli_w.dumps(data))
    args = ["run", tmp_path / "case.toml", "-o", tmp_path / "o.h5", "-q"]
    assert judge(invoke(args, seconds=120, cwd=tmp_path), tmp_path).kind == "ok"
    data["solver"]["t_end"] = 1000.0
    (tmp_path / "case.toml").write_text(tomli_w.dumps(data))
    outcome = judge(invoke(args, seconds=60, cwd=tmp_path, long_after=4.0), tmp_path)
    assert outcome.kind == "long" and outcome.good, outcome
    assert re.search(r"t = [0-9.e+-]+ s after [1-9][0-9]* steps", outcome.detail), outcome

    start = time.process_time()
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(fuzzing, "WALL_FACTOR", 1e3)
        with pytest.raises(Hang, match="after 0.6 s of processor time") as caught:
            with time_limit(0.6, long_after=0.2):
                while time.process_time() - start < 10.0:
                    pass
    assert not isinstance(caught.value, Long)
    assert 0.5 <= time.process_time() - start < 3.0


# --- a node that starts on an obstacle within round-off -----------------------------------------


@pytest.mark.parametrize("z", [5e-324, 1e-300, 1e-14])
def test_a_node_on_the_seabed_within_round_off_is_bad_input(tmp_path, z):
    """The long run's seed 12: the rough-seabed mooring with a node at z = 5e-324 over the
    seabed z = 0 (a gap of the smallest number there is) ended in exit 1 at t = 0 with its
    kept start's residual written as inf (the barrier's force kappa dhat^2 / d overflows).
    A node within the round-off of its coordinates (20 m: about 4e-12 m) of an obstacle
    starts on it: exit 2 naming the obstacle and the node, nothing written. 1e-9 m above
    the bed is a start like any other."""
    import tomllib

    import tomli_w
    from fuzzing import CONFIGS, small

    data = small(tomllib.loads((CONFIGS / "friction" / "mooring_pulled.toml").read_text()))
    data["geometry"]["nodes"][5][2] = z
    result, text = run(tmp_path, "-o", tmp_path / "o.h5", case=tomli_w.dumps(data))
    assert result.exit_code == 2, text
    assert "obstacle[0] (kind 'plane'): node 5 at [20.935, 0.0, " in text, text
    assert "starts inside or on it" in text and judge(result, tmp_path).good
    assert not (tmp_path / "o.h5").exists()
    data["geometry"]["nodes"][5][2] = 1e-9
    result, text = run(tmp_path, "-o", tmp_path / "o.h5", case=tomli_w.dumps(data))
    assert result.exit_code == 0 and judge(result, tmp_path, set()).good, text


@pytest.mark.parametrize("kind", ["box", "sphere"])
def test_a_free_body_beyond_the_resolution_of_its_coordinates_is_bad_input(tmp_path, kind):
    """Seed 14: the capture scene's 8000 kg box moved to y = -1e99 m. Its rigidity's
    forces overflowed and the run kept a state whose residual was inf; a free body whose
    coordinates' round-off is beyond 1e-8 of its size is refused, its key named (at 1e9 m
    the run had also failed: its rigidity's noise, 87 N, hid the net's residual)."""
    shape = {  # a sphere with a mass alone is a ball: a density makes it a free body
        "box": "half_size = [1.0, 1.0, 1.0]\nmass = 10.0",
        "sphere": "radius = 1.0\ndensity = 100.0",
    }[kind]
    case = small_net("dynamic", t_end=0.05) + (
        f'\n[[obstacle]]\nkind = "{kind}"\ncenter = [0.0, -1e99, 0.0]\n{shape}\n'
    )
    path = tmp_path / "case.toml"
    path.write_text(case)
    out = tmp_path / "o.h5"
    result = invoke(["run", path, "-o", out, "-q"])
    assert result.exit_code == 2, result.output
    assert "obstacle[0].center = [0.0, -1e99, 0.0]" in result.output, result.output
    assert "not resolved against its size" in result.output and not out.exists()
    near = case.replace("-1e99", "-1e6")  # 1e6 m: its size resolved to 2e-10
    path.write_text(near)
    result = invoke(["run", path, "-o", out, "-q"])
    assert result.exit_code == 0, result.output


def test_mutations_never_change_the_hostile_values_they_draw_from():
    """A mutation that put one of HOSTILE's lists or tables into a case and a later one
    that changed it in place changed HOSTILE for every later draw; hypothesis then found
    its data generation inconsistent on a replay (FlakyStrategyDefinition in a fresh
    clone's run) and lost what it replayed. Each draw is a copy now."""
    import copy
    import random

    import fuzzing

    before = copy.deepcopy(fuzzing.HOSTILE)
    rng = random.Random(0)
    for _ in range(2000):
        data = {"geometry": {"kind": "cable", "nodes": 5}, "solver": {"dt": 0.1}}
        for _ in range(3):
            fuzzing.mutate_case(data, rng)
    assert repr(fuzzing.HOSTILE) == repr(before)


# --- a time step too short to step with ---------------------------------------------------------


@pytest.mark.parametrize("key, value", [("dt", "1e-300"), ("dt_min", "1e-200")])
def test_a_time_step_too_short_to_step_with_is_bad_input(tmp_path, key, value):
    """The long run of seed 90210: tests/fuzz/cases/drop_to_rest.toml with solver.dt =
    1e-300 (a run to rest: no t_end bounds its steps) stopped with an internal error
    (1 / dt^2 overflows to a division by zero); from about 1e-80 s the step's forces
    overflow. A dt, dt_min or dt_max below 1e-50 s is bad input naming the key; 1e-30 s
    steps on (its run to rest grows its steps from there)."""
    from fuzzing import SEEDS

    case = (SEEDS / "drop_to_rest.toml").read_text()
    extra = [] if key == "dt" else ["--set", "solver.tolerance=1e-3", "--set", "solver.t_end=0.1"]
    args = ["-o", tmp_path / "o.h5", "--set", f"solver.{key}={value}", *extra]
    result, text = run(tmp_path, *args, case=case)
    assert result.exit_code == 2, text
    assert f"solver.{key} = {float(value)!r}: too short to step with" in text, text
    assert "give at least 1e-50 s" in text and judge(result, tmp_path).good
