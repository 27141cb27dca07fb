"""The quick tier of the fuzzing suite: hostile mutations of every example case, of case
files built from the declared keys, of net files, sweep values and result files, each run
through the command it is meant for, in this process and bounded in time.

Every outcome must be one of: exit 0 with finite numbers in every file written; exit 2
with a message naming what was wrong (no NumPy reprs) and nothing written; exit 1 with
catenet's message. Never a traceback, a hang, another exit code, a non-finite result or a
hidden file left behind (tests/fuzzing.py judges). The long run is benchmarks/fuzz.py.
"""

from __future__ import annotations

import copy
import random
import tomllib
from pathlib import Path

import pytest
from fuzzing import (
    NET_CASE,
    NET_FILES,
    SWEEP_CASE,
    command_for,
    copy_beside,
    example_cases,
    invoke,
    judge,
    mutate_case,
    mutate_params,
    mutate_result,
    mutate_text,
    render,
    small,
)
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

pytestmark = pytest.mark.filterwarnings("ignore")

SETTINGS = dict(
    deadline=None,
    derandomize=False,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
#: Processor seconds after which a dynamic run still taking steps is judged long, not hung
#: (a mutation that removes solver.t_end runs a capture for its default 10 s).
LONG = 10.0
CASES = [p for p in example_cases() if "sweeps" not in p.parts]
BASES = {p: small(tomllib.loads(p.read_text())) for p in CASES}


def _check(outcome, what) -> None:
    assert outcome.good, f"{outcome.kind}: {outcome.detail}\n  input: {what}"


def _fresh(tmp_path_factory, case: Path | None = None) -> Path:
    work = tmp_path_factory.mktemp("fuzz")
    if case is not None:
        copy_beside(case, work)
    return work


@settings(max_examples=120, **SETTINGS)
@given(index=st.integers(0, len(CASES) - 1), rng=st.randoms(use_true_random=False))
def test_mutated_example_cases(tmp_path_factory, index, rng):
    """Each example case of configs/ (made small), one to three mutations, then
    ``catenet run`` (or ``formfind`` for a form-finding case)."""
    case = CASES[index]
    data = copy.deepcopy(BASES[case])
    notes = mutate_case(data, rng)
    work = _fresh(tmp_path_factory, case)
    path = work / "case.toml"
    path.write_bytes(render(data, rng))
    command, *extra = command_for(data, rng)
    args = [command, path, "-o", work / "out.h5", *extra]
    result = invoke([*args, "-q"], seconds=60, cwd=work, long_after=LONG)
    _check(judge(result, work), f"{case.name}: {notes}")


@settings(max_examples=40, **SETTINGS)
@given(rng=st.randoms(use_true_random=False))
def test_case_files_from_the_declared_keys(tmp_path_factory, rng):
    """A case built from the declared keys of every section (their defaults where they
    have one, a hostile value for some), so that keys no example uses are reached."""
    from catenet.case.keys import REQUIRED, declared
    from catenet.case.material import MaterialConfig
    from catenet.case.sections import LoadConfig, OutputConfig, SolverConfig

    data = copy.deepcopy(BASES[rng.choice(CASES)])
    for name, section in (
        ("material", MaterialConfig),
        ("load", LoadConfig),
        ("solver", SolverConfig),
        ("output", OutputConfig),
    ):
        table = data.setdefault(name, {})
        if not isinstance(table, dict):
            continue
        for key in declared(section):
            if key.default is REQUIRED or key.computed or rng.random() < 0.7:
                continue
            if rng.random() < 0.5 and isinstance(key.default, (int, float, str, bool)):
                table[key.name] = key.default
            else:
                table[key.name] = rng.choice([None, 1e300, -1, 0, "x", [], 10**20, float("nan")])
    data = _drop_none(data)
    work = _fresh(tmp_path_factory)
    path = work / "case.toml"
    path.write_bytes(render(data, rng))
    args = ["run", path, "-o", work / "out.h5", "-q"]
    result = invoke(args, seconds=60, cwd=work, long_after=LONG)
    _check(judge(result, work), data)


def _drop_none(v):
    if isinstance(v, dict):
        return {k: _drop_none(x) for k, x in v.items() if x is not None}
    if isinstance(v, list):
        return [_drop_none(x) for x in v if x is not None]
    return v


@settings(max_examples=60, **SETTINGS)
@given(name=st.sampled_from(sorted(NET_FILES)), rng=st.randoms(use_true_random=False))
def test_mutated_net_files(tmp_path_factory, name, rng):
    work = _fresh(tmp_path_factory)
    (work / name).write_bytes(mutate_text(NET_FILES[name], rng))
    case = work / "case.toml"
    case.write_text(NET_CASE.format(name=name))
    result = invoke(["run", case, "-o", work / "out.h5", "-q"], seconds=60, cwd=work)
    _check(judge(result, work), (work / name).read_bytes()[:300])


MESH_CASE = """
title = "a cable over a mesh"
[geometry]
kind = "cable"
start = [-2.0, 0.0, 1.2]
end = [2.0, 0.0, 1.2]
nodes = 21
[material]
EA = 1000.0
radius = 0.01
density = 1000.0
[load]
gravity = [0.0, 0.0, -9.81]
[[obstacle]]
kind = "mesh"
file = "cube.stl"
[solver]
method = "static"
"""


@settings(max_examples=30, **SETTINGS)
@given(rng=st.randoms(use_true_random=False))
def test_mutated_mesh_files(tmp_path_factory, rng):
    import meshio
    from meshes import CUBE_T, CUBE_V

    work = _fresh(tmp_path_factory)
    mesh = work / "cube.stl"
    meshio.write_points_cells(mesh, CUBE_V * 2 - 1, [("triangle", CUBE_T)], binary=False)
    mesh.write_bytes(mutate_text(mesh.read_bytes(), rng))
    case = work / "case.toml"
    case.write_text(MESH_CASE)
    result = invoke(["run", case, "-o", work / "out.h5", "-q"], seconds=60, cwd=work)
    _check(judge(result, work), mesh.read_bytes()[:300])


@settings(max_examples=60, **SETTINGS)
@given(rng=st.randoms(use_true_random=False))
def test_mutated_sweep_values(tmp_path_factory, rng):
    work = _fresh(tmp_path_factory)
    case = work / "case.toml"
    params = mutate_params(rng)
    if rng.random() < 0.3:  # the same values in a [sweep] table
        key, _, values = params[0].partition("=")
        case.write_text(SWEEP_CASE + f'\n[sweep]\n"{key}" = "{values}"\n')
        args = ["sweep", case, "-o", work / "sw", "-j", "1", "-q"]
    else:
        case.write_text(SWEEP_CASE)
        args = ["sweep", case, "-o", work / "sw", "-j", "1", "-q"]
        for p in params:
            args += ["-p", p]
    result = invoke(args, seconds=60, cwd=work)
    _check(judge(result, work), params)


@pytest.fixture(scope="module")
def result_files(tmp_path_factory):
    """A dynamic and a static run's files, to be damaged."""
    from conftest import small_net

    work = tmp_path_factory.mktemp("results")
    files = {}
    for method, t_end in (("dynamic", 0.3), ("static", 1.0)):
        case = work / f"{method}.toml"
        case.write_text(small_net(method=method, t_end=t_end).replace("0.05", "0.1"))
        out = work / f"{method}.h5"
        result = invoke(["run", case, "-o", out, "-q"], seconds=120)
        assert result.exit_code == 0, result.output
        files[method] = (case, out)
    return files


@settings(max_examples=80, **SETTINGS)
@given(
    method=st.sampled_from(["dynamic", "static"]),
    command=st.sampled_from(["plot", "export", "repair", "restart", "report"]),
    rng=st.randoms(use_true_random=False),
)
def test_damaged_result_files(tmp_path_factory, result_files, method, command, rng):
    case, src = result_files[method]
    work = _fresh(tmp_path_factory)
    damaged = work / "damaged.h5"
    how = mutate_result(src, damaged, rng)
    before = set(work.rglob("*.h5"))
    if command == "plot":
        args = ["plot", damaged, "-o", work / "fig.png"]
    elif command == "export":
        args = ["export", damaged, "--to", rng.choice(["vtu", "xdmf"]), "-o", work / "ex"]
    elif command == "repair":
        args = ["repair", damaged]
    elif command == "report":
        args = ["report", damaged, "--format", rng.choice(["md", "csv", "html"])]
        args += ["-o", work / "report"]
    else:
        args = ["run", case, "--restart", damaged, "-o", work / "again.h5", "-q"]
        args += ["--set", "solver.t_end=0.6", "--set", "solver.method=dynamic"]
    result = invoke(args, seconds=60, cwd=work)
    before.discard(damaged)
    _check(judge(result, work, before | {damaged}), f"{method} file {how}, {command}")


def test_the_mutations_reach_every_example():
    """The suite's cases are the examples of configs/ (sweeps aside), each small enough."""
    names = {p.name for p in CASES}
    assert {"catenary.toml", "guyed_mast.toml", "ball_off_box.toml", "saddle.toml"} <= names
    rng = random.Random(0)
    for base in BASES.values():
        data = copy.deepcopy(base)
        assert mutate_case(data, rng) and isinstance(render(data, rng), bytes)
