"""Nothing a user can type gives a traceback; the same run gives the same bits.

Property-based tests (hypothesis) feed the Python API and the command line random and
hostile input: each call either works or raises ConfigError (exit code 2, one message
with the key path, no output file left behind). Case-file parsing has its own property
tests in test_case.py.
"""

from __future__ import annotations

import math

import h5py
import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import catenet as cn
from catenet.cli import main
from catenet.model import builders as geometry

MAT = cn.Material.from_E(10e6, radius=0.01, density=1000.0)

numbers = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-(10**12), 10**12),
    st.sampled_from([0, -1, 1e-300, 1e300, math.nan, math.inf, -math.inf]),
)
junk = st.one_of(
    numbers, st.text(max_size=5), st.none(), st.booleans(), st.lists(numbers, max_size=4)
)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    nodes=st.one_of(
        st.lists(st.lists(numbers, min_size=0, max_size=4), max_size=6),
        junk,
    ),
    edges=st.one_of(
        st.lists(st.lists(st.integers(-3, 8), min_size=0, max_size=3), max_size=8), junk
    ),
    fixed=st.one_of(st.lists(st.integers(-3, 8), max_size=4), junk),
    ea=st.one_of(numbers, st.lists(numbers, max_size=8)),
    rest=st.one_of(st.none(), numbers, st.lists(numbers, max_size=8)),
)
def test_net_from_arrays_accepts_or_explains(nodes, edges, fixed, ea, rest):
    try:
        net = cn.Net.from_arrays(nodes, edges, EA=ea, fixed=fixed, rest_length=rest)
    except cn.ConfigError as exc:
        assert exc.problems and all(isinstance(p, str) and p for p in exc.problems)
        return
    # What is accepted is a sound net.
    assert np.all(np.isfinite(net.nodes)) and np.all(net.rest_length > 0)
    assert np.all(net.EA > 0) and net.fixed.any()


@settings(max_examples=100, deadline=None)
@given(
    n=st.one_of(st.integers(-4, 40), numbers),
    alpha=numbers,
    size=numbers,
    edge=numbers,
)
def test_square_net_accepts_or_explains(n, alpha, size, edge):
    # Hostile sizes stay small here: at the real cap (MAX_NODES, or what this machine's
    # memory takes) hypothesis builds nets of millions of nodes, minutes and GiB each,
    # and several test processes at once can run the machine out of memory.
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(geometry, "MAX_NODES", 200_000)
        try:
            sq = cn.square_net(n, alpha, size, edge, MAT)
        except cn.ConfigError as exc:
            assert "geometry." in str(exc)
            return
    assert 3 <= sq.net.n_nodes <= 200_000 and sq.net.fixed.any()


def test_builders_refuse_a_net_this_machine_cannot_hold(monkeypatch):
    """The Python API checks memory too (the case loader does so with a margin before):
    a net whose solve cannot fit is a ConfigError naming the key, never an OOM kill."""
    from catenet.model import memory

    monkeypatch.setattr(memory, "physical_memory", lambda: 2**30)  # 1 GiB
    with pytest.raises(cn.ConfigError, match=r"geometry.edge_length = 0.0001.*GiB; this mach"):
        cn.square_net(34, 0.3, 1.0, 1e-4, MAT)  # ~7e5 nodes: about 1.9 GiB
    with pytest.raises(cn.ConfigError, match=r"geometry.nodes = 2000000: .*1 GiB"):
        cn.cable([0, 0, 0], [1, 0, 0], 2_000_000, MAT)
    assert cn.square_net(34, 0.3, 1.0, 1e-2, MAT).net.n_nodes > 1000  # a small one is fine


BASE_CASE = """
title = "robustness"
[geometry]
kind = "square_net"
n = 10
alpha = 0.3
size = 1.0
edge_length = 0.1
[material]
E = 10e6
radius = 0.01
density = 1000.0
[load]
pressure = 50.0
[solver]
method = "static"
[output]
file = "out/r.h5"
every = 1
"""

KEYS = [
    "geometry.n",
    "geometry.alpha",
    "geometry.size",
    "geometry.edge_length",
    "geometry.kind",
    "material.E",
    "material.radius",
    "material.density",
    "material.tension_only",
    "load.pressure",
    "load.gravity",
    "solver.method",
    "solver.dt",
    "solver.damping",
    "solver.t_end",
    "solver.rtol",
    "solver.linear",
    "solver.threads",
    "solver.steps",
    "solver.max_iter",
    "output.every",
    "output.file",
    "nonsense.key",
    "geometry",
]
VALUES = st.one_of(
    st.sampled_from(
        [
            "nan",
            "inf",
            "-inf",
            "-1",
            "0",
            "1e400",
            "[]",
            "[1, 2]",
            '"x"',
            "true",
            "{a = 1}",
            "[0, 0, -9.81]",
            "2",
            "0.5",
            "dynamic",
            "1e-300",
            "3.5",
            "",
            "=",
            "[[1]]",
            "'pardiso'",
            "1e9",
        ]
    ),
    st.text(alphabet=st.characters(blacklist_categories=("Cs",)), max_size=8),
)


@pytest.mark.filterwarnings("ignore")
@settings(
    max_examples=60,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(sets=st.lists(st.tuples(st.sampled_from(KEYS), VALUES), min_size=1, max_size=3))
def test_no_command_line_input_gives_a_traceback(tmp_path_factory, sets):
    """Random --set overrides of a small case: exit 0 (ran), 1 (ran, failed) or 2 (bad
    input, nothing written); never a traceback."""
    work = tmp_path_factory.mktemp("cli")
    case = work / "case.toml"
    case.write_text(BASE_CASE)
    out = work / "result.h5"
    args = ["run", str(case), "-o", str(out), "-q"]
    for key, value in sets:
        args += ["--set", f"{key}={value}"]
    result = CliRunner().invoke(main, args, catch_exceptions=True)
    text = result.output + (result.stderr if result.stderr_bytes is not None else "")
    assert "Traceback" not in text
    assert result.exit_code in (0, 1, 2), (args, text, result.exception)
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    if result.exit_code == 2:
        assert not out.exists() and not out.with_suffix(".xdmf").exists()
        assert text.strip()


def test_garbage_case_file_gives_exit_2(tmp_path):
    case = tmp_path / "bad.toml"
    case.write_bytes(b"\x00\xff[geometry\nkind = ")
    result = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "o.h5")])
    assert result.exit_code == 2 and "Traceback" not in result.output
    assert not (tmp_path / "o.h5").exists()


def test_same_case_same_bits(tmp_path):
    """Determinism: the same case with the same thread count gives bit-identical files."""
    case = tmp_path / "case.toml"
    case.write_text(BASE_CASE.replace('"static"', '"dynamic"\ndt = 0.05\nt_end = 1.0'))
    runs = []
    for name in ("a.h5", "b.h5"):
        result = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / name), "-q"])
        assert result.exit_code == 0, result.output
        with h5py.File(tmp_path / name) as h5:
            runs.append({k: h5[k][()] for k in ("result/x", "result/tension", "trajectory/x")})
    for key in runs[0]:
        assert np.array_equal(runs[0][key], runs[1][key]), key


@pytest.mark.roundoff
def test_singular_systems_name_their_nodes():
    """A matrix without stiffness at some DOFs is reported with the nodes concerned."""
    from catenet.solver.static import Workspace

    sq = cn.square_net(2, 0.0, 1.0, 0.25, MAT)  # flat and unstressed: no transverse stiffness
    ws = Workspace(sq.net)
    data = ws.system.hessian(sq.net.nodes)
    with pytest.raises(cn.SingularSystemError) as info:
        ws.solver.factorize(data)
        ws.solver.solve(np.ones(ws.system.n_free))
    free = set(np.flatnonzero(~sq.net.fixed).tolist())
    assert info.value.nodes and set(info.value.nodes) <= free
    assert "nodes concerned" in str(info.value)
