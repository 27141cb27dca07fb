"""Graph cases with cables (tests/case/test_cables.py, test_cable_input.py): small cases and
the check that a case is refused with the expected messages."""

from __future__ import annotations

import pytest

from catenet.case import parse_case
from catenet.errors import ConfigError


def two_cables() -> dict:
    """A horizontal cable "a" (0 -> 1, 4 m) and a cable "b" across it (2 -> 3), all four
    ends pinned through the node set "anchors"."""
    return {
        "geometry": {
            "kind": "graph",
            "nodes": [[0, 0, 0], [4, 0, 0], [2, -2, 0.5], [2, 2, 0.5]],
            "edge_length": 0.5,
            "sets": {"anchors": [0, 1, 2, 3], "west": [0]},
            "cable": [
                {"name": "a", "nodes": ["west", 1], "prestress": 100.0},
                {"name": "b", "nodes": [2, 3], "material": {"EA": 5e4}},
            ],
        },
        "supports": {"fixed": ["anchors"]},
        "material": {"EA": 1e5},
    }


def straight(**cable) -> dict:
    """One straight cable through three given nodes, pinned at its ends."""
    return {
        "geometry": {
            "kind": "graph",
            "nodes": [[0, 0, 0], [1.5, 0.5, 1], [3, 1, 2]],
            "fixed": [0, 2],
            "edge_length": 0.3,
            "cable": [{"name": "c", "nodes": [0, 1, 2], **cable}],
        },
        "material": {"EA": 1000.0},
    }


def problems(data: dict, **kw) -> list[str]:
    with pytest.raises(ConfigError) as info:
        parse_case(data, **kw)
    return info.value.problems


def one(data: dict, needle: str) -> str:
    found = problems(data)
    assert len(found) == 1 and needle in found[0], found
    return found[0]
