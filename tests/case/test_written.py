"""Numbers quoted in messages as the user wrote them (catenet/case/written.py): in the
case file and in --set, floats and integers in every TOML spelling, on several keys; and
the numbers themselves unchanged (values, copies, pickles, the resolved case)."""

from __future__ import annotations

import copy
import pickle
import tomllib

import pytest
from conftest import small_net

from catenet.case import dumps_toml, load_case, parse_toml
from catenet.case.written import WrittenFloat, WrittenInt
from catenet.errors import ConfigError

CASE = small_net(method="dynamic", dt=0.01, t_end=0.3)


def problems(tmp_path, case: str = CASE, sets=()) -> str:
    path = tmp_path / "case.toml"
    path.write_text(case)
    with pytest.raises(ConfigError) as info:
        load_case(path, list(sets))
    return str(info.value)


@pytest.mark.parametrize(
    "key, text",
    [
        ("material.E", "-1e12"),
        ("material.E", "-1E+12"),
        ("material.E", "-1_000.5"),
        ("material.density", "-inf"),
        ("material.radius", "nan"),
        ("solver.dt", "1e400"),
        ("solver.dt", "-0.0"),
        ("solver.damping", "-5e-3"),
        ("solver.steps", "0x0"),
        ("solver.steps", "-1_000"),
        ("solver.max_iter", "0b0"),
        ("solver.max_iter", "0o0"),
        ("solver.max_iter", "+0"),
        ("geometry.n", "0x3"),
    ],
)
def test_a_value_in_set_is_quoted_as_written(tmp_path, key, text):
    shown = problems(tmp_path, sets=[f"{key}={text}"])
    assert f"{key} = {text}:" in shown, shown
    assert "np." not in shown


@pytest.mark.parametrize(
    "line, text",
    [
        ("E = 10e6", "E = 1e300"),
        ("E = 10e6", "E = -2.5E3"),
        ("E = 10e6", "E = 1_0e-400"),
        ("radius = 0.01", "radius = 0x0"),
        ("density = 1000.0", "density = -1_000"),
    ],
)
def test_a_value_in_the_case_file_is_quoted_as_written(tmp_path, line, text):
    assert line in CASE
    shown = problems(tmp_path, CASE.replace(line, text))
    key, value = (s.strip() for s in text.split("="))
    assert f"material.{key} = {value}:" in shown, shown


def test_integers_in_tables_and_arrays_of_tables(tmp_path):
    """An integer's text is found in the line of its key, below [table] and [[array]]
    headers; other lines (and multi-line strings) leave the numbers alone."""
    text = """
title = '''
x = 0x5
'''
[solver]
steps = 0x10  # sixteen
[[mass]]
node = 1
mass = 1_0
[[mass]]
node = 0b11
mass = 2.0
[mass.extra]
k = 0o7
"""
    data = parse_toml(text, "t.toml", written=True)
    assert repr(data["solver"]["steps"]) == "0x10" and data["solver"]["steps"] == 16
    assert repr(data["mass"][0]["mass"]) == "1_0" and repr(data["mass"][0]["node"]) == "1"
    assert repr(data["mass"][1]["node"]) == "0b11" and data["mass"][1]["node"] == 3
    assert repr(data["mass"][1]["extra"]["k"]) == "0o7"
    assert data["title"] == "x = 0x5\n"
    assert type(parse_toml(text, "t.toml")["solver"]["steps"]) is int  # not asked for


def test_written_numbers_are_numbers():
    f, i = WrittenFloat("1_000.5e1"), WrittenInt(16, "0x10")
    assert f == 10005.0 and f + 1 == 10006.0 and type(f + 1) is float
    assert i == 16 and list(range(i))[-1] == 15 and type(i + 0) is int
    assert float(f) == 10005.0 and type(float(f)) is float and type(int(i)) is int
    for value in (f, i):
        for again in (copy.deepcopy(value), pickle.loads(pickle.dumps(value))):
            assert again == value and repr(again) == repr(value)
    table = {"a": f, "b": i, "c": [WrittenFloat("inf"), WrittenFloat("-5E-3")]}
    assert tomllib.loads(dumps_toml(table)) == table  # written back, read back the same


def test_a_valid_case_reads_the_same(tmp_path):
    """The spelling changes messages only: the case's values, its resolved table and TOML
    are those of Python's spelling (plain numbers), and its counts are plain integers."""
    path = tmp_path / "a.toml"
    path.write_text(CASE.replace("E = 10e6", "E = 1_0e6").replace("n = 10", "n = 0xA"))
    plain = tmp_path / "b.toml"
    plain.write_text(CASE.replace("E = 10e6", "E = 10000000.0"))
    a, b = load_case(path, ["solver.dt=1e-2"]), load_case(plain, ["solver.dt=0.01"])
    assert a == b and a.material.E == 1e7 and a.solver.dt == 0.01
    assert repr(a.material.E) == "1_0e6" and repr(a.solver.dt) == "1e-2"  # for messages
    assert a.geometry.n == 10 and type(a.geometry.n) is int
    assert a.to_toml() == b.to_toml() and a.to_dict() == b.to_dict()
    assert type(a.to_dict()["material"]["E"]) is float


def test_show_never_prints_numpy_reprs():
    """A value a message quotes that is not the user's text (a built array, a NumPy
    scalar inside a list) reads as Python's numbers, shortened; the user's text as is."""
    import numpy as np

    from catenet.case.keys import show

    assert show([np.float64(1.5), np.int64(2), WrittenFloat("1e12")]) == "[1.5, 2, 1e12]"
    assert show(np.array([1.0, np.inf])) == "[1.0, inf]" and show(np.float64("nan")) == "nan"
    assert show((WrittenInt(16, "0x10"),)) == "[0x10]" and show((1, 2)) == "[1, 2]"
    long = show(np.arange(10_000.0))
    assert len(long) <= 72 and long.endswith(" ...") and "np." not in long
    assert show([[1, 2], [3]]) == "[[1, 2], [3]]" and show("ab") == "'ab'"
    assert show(True) == "true" and show([np.bool_(False), None]) == "[false, None]"


def test_messages_echo_arrays_and_booleans_as_toml_writes_them(tmp_path):
    """An area load's node array is kept as a tuple once checked, and a boolean is
    Python's True: the message still quotes them as the case file wrote them, a TOML
    array in brackets and true (never the Python tuple (0, 2, ...) or True)."""
    from catenet.case import build

    net = (
        '[geometry]\nkind = "graph"\n'
        "nodes = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 0]]\n"
        "edges = [[0, 1], [1, 2], [2, 3], [3, 0], [0, 4], [1, 4], [2, 4], [3, 4]]\n"
        "fixed = [0, 1, 2, 3]\n[material]\nEA = 1e6\n"
    )
    (tmp_path / "a.toml").write_text(net + "[[load.area]]\npressure = 100.0\nnodes = [0, 1]\n")
    with pytest.raises(ConfigError) as bad:
        build(load_case(tmp_path / "a.toml"))
    assert "load.area[0].nodes = [0, 1]: " in str(bad.value)
    with pytest.raises(ConfigError) as bad:
        load_case(tmp_path / "a.toml", ["material.EA=true"])
    assert "material.EA = true: must be a number" in str(bad.value)
