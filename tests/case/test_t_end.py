"""solver.t_end: a number or "rest", and its default decided by what depends on time
(catenet/case/timing.py): "rest" where nothing does, 10 s otherwise."""

from __future__ import annotations

import copy

import pytest

from catenet.case import parse_case
from catenet.errors import ConfigError


def cable(**solver) -> dict:
    """A hanging cable under gravity; nothing in it depends on time."""
    return {
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [10, 0, 0], "nodes": 21},
        "material": {"E": 2e11, "radius": 0.005, "density": 7850.0},
        "load": {"gravity": [0, 0, -9.81]},
        "solver": {"method": "dynamic", **solver},
    }


def with_(data: dict, path: str, value) -> dict:
    out = copy.deepcopy(data)
    *head, last = path.split(".")
    node = out
    for k in head:
        node = node.setdefault(k, {})
    node[last] = value
    return out


def test_the_default_is_rest_where_nothing_depends_on_time():
    assert parse_case(cable()).solver.t_end == "rest"
    assert parse_case(with_(cable(), "solver.method", "static")).solver.t_end is None
    assert parse_case(cable(damping=0.1)).solver.t_end == "rest"


@pytest.mark.parametrize(
    "path, value",
    [
        ("load.history", [[0.0, 0.0], [1.0, 1.0]]),
        ("load.point", [{"node": 10, "force": [0, 0, -1], "history": [[0, 1], [2, 0]]}]),
        ("supports.move", [{"node": 0, "displacement": [0.1, 0, 0], "duration": 1.0}]),
        ("supports.move", [{"node": 0, "displacement": [0.1, 0, 0], "history": [[0, 0], [1, 1]]}]),
        ("mass", [{"node": 10, "velocity": [0, 0, 1.0]}]),
        ("obstacle", [{"kind": "sphere", "center": [5, 0, -2], "radius": 0.5, "mass": 10.0}]),
        (
            "obstacle",
            [{"kind": "sphere", "center": [5, 0, -2], "radius": 0.5, "velocity": [0, 0, 1]}],
        ),
        ("solver.damping", 0.0),
    ],
)
def test_anything_that_depends_on_time_keeps_ten_seconds(path, value):
    case = parse_case(with_(cable(), path, value))
    assert case.solver.t_end == 10.0
    # ... and no damping it did not ask for: its motion is the answer (a pendulum struck
    # by a pulse swung out half as far at the paper's 1 1/s)
    assert case.solver.damping == 0.0


def test_damping_is_the_papers_only_in_dynamic_relaxation():
    """solver.damping's default: 1 1/s where nothing depends on time (dynamic relaxation,
    to rest or to a t_end given), 0 where the motion is the answer or in water; a given
    value is kept."""
    assert parse_case(cable()).solver.damping == 1.0
    assert parse_case(cable(t_end=5.0)).solver.damping == 1.0
    moving = with_(cable(), "load.history", [[0.0, 0.0], [1.0, 1.0]])
    assert parse_case(moving).solver.damping == 0.0
    assert parse_case(with_(moving, "solver.damping", 0.5)).solver.damping == 0.5


def test_a_support_moved_at_once_does_not_depend_on_time():
    move = [{"node": 0, "displacement": [0.1, 0, 0]}]  # duration 0: displaced at t = 0
    assert parse_case(with_(cable(), "supports.move", move)).solver.t_end == "rest"


def test_an_explicit_t_end_is_kept_and_written_back():
    for t_end in (2.5, "rest"):
        case = parse_case(cable(t_end=t_end))
        assert case.solver.t_end == t_end
        again = parse_case(case.to_dict())
        assert again.solver.t_end == t_end and again == case
    # a resolved default reads the same
    resolved = parse_case(with_(cable(), "solver.damping", 0.0))
    assert parse_case(resolved.to_dict()).solver.t_end == 10.0


@pytest.mark.parametrize(
    "value, message",
    [
        ("fast", "solver.t_end = 'fast': must be a number > 0 or 'rest'"),
        (-1.0, "solver.t_end = -1.0: must be finite and > 0, or 'rest'"),
        (True, "solver.t_end = true: must be a number, finite and > 0, or 'rest'"),
    ],
)
def test_bad_t_end_names_the_key_the_value_and_what_is_accepted(value, message):
    with pytest.raises(ConfigError) as info:
        parse_case(cable(t_end=value))
    assert message in info.value.problems


def test_max_steps_is_a_positive_integer():
    assert parse_case(cable(max_steps=50)).solver.max_steps == 50
    with pytest.raises(ConfigError) as info:
        parse_case(cable(max_steps=0))
    assert "solver.max_steps = 0: must be an integer >= 1" in info.value.problems


def test_rest_skips_the_end_time_checks_of_dt():
    # dt > t_end is refused for a number, meaningless for "rest"
    with pytest.raises(ConfigError, match="must be <= solver.t_end"):
        parse_case(cable(dt=2.0, t_end=1.0))
    assert parse_case(cable(dt=2.0)).solver.t_end == "rest"
