"""Rod ends on coupled 6x6 springs (``[[supports.spring]]`` with a 6x6 ``stiffness``): a
foundation holding a rod's end node and direction together. Against a closed form: a
cantilever of length L on a 6x6 base K (world axes, coupled) under a small tip load P
deflects as the rigid-base beam plus the base's flexibility carried to the tip,

    delta = G K^-1 G^T P + (P L^3 / (3 EI)) (1 - e e^T) P / |P|  (P across the rod),

G = [1, -[r]x] with r = L e the tip's arm: the base takes the wrench (P, r x P), moves by
u and turns by theta = (K^-1 wrench), and carries the tip by u + theta x r (coupling
terms included). The six reaction components balance the load in the deformed state;
a stiff base is the clamp; bad input exits 2 naming the key."""

from __future__ import annotations

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.case import dumps_toml
from catenet.cli import main

EI, L, P = 2.0, 1.5, 1e-4  # N m^2, m, N: P L^2 / EI ~ 1e-4, linear


def _rotation(axis, angle) -> np.ndarray:
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def _cross(v) -> np.ndarray:
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


#: A base in its own axes (rod along local z): soft sideways, coupled sway and rocking
#: (a footing: pushing it along x rocks it about y), stiff in heave and torsion.
LOCAL = np.array(
    [
        [2.0, 0.0, 0.0, 0.0, 1.2, 0.0],
        [0.0, 3.0, 0.0, -1.0, 0.0, 0.0],
        [0.0, 0.0, 50.0, 0.0, 0.0, 0.0],
        [0.0, -1.0, 0.0, 4.0, 0.0, 0.0],
        [1.2, 0.0, 0.0, 0.0, 2.5, 0.0],
        [0.0, 0.0, 0.0, 0.0, 0.0, 9.0],
    ]
)


#: LOCAL with its twist about the rod (rz) coupled with rocking about x: refused at the
#: end of a rod that twists (an uncoupled twist row is held in series with the rod).
COUPLED = LOCAL.copy()
COUPLED[3, 5] = COUPLED[5, 3] = 0.5

START = np.array([1.0, -2.0, 0.5])


def _case(rot: np.ndarray, k6: np.ndarray, load: np.ndarray, nodes: int = 61) -> dict:
    e = rot @ [0.0, 0.0, 1.0]
    return {
        "geometry": {
            "kind": "cable", "start": START.tolist(), "end": (START + L * e).tolist(),
            "nodes": nodes,
        },
        "material": {"EA": 1e7, "EI": EI},
        "supports": {"fixed": [], "spring": [{"nodes": ["start"], "stiffness": k6.tolist()}]},
        "load": {"point": [{"node": "end", "force": load.tolist()}]},
        "solver": {"rtol": 1e-10},
    }  # fmt: skip


def run(tmp_path, data) -> dict:
    case = tmp_path / "case.toml"
    case.write_text(dumps_toml(data))
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "r.h5")])
    assert done.exit_code == 0, done.output
    with h5py.File(tmp_path / "r.h5") as f:
        return {
            k: f[k][:]
            for k in (
                "result/x", "mesh/nodes", "result/reaction", "result/reaction_moment",
                "result/bending_moment", "result/curvature",
            )
        }  # fmt: skip


@pytest.mark.parametrize(
    "axis, angle, side",
    [([1.0, 0.0, 0.0], 0.0, [1.0, 0.3, 0.0]), ([1.0, 2.0, -0.5], 1.1, [0.2, -1.0, 0.4])],
)
def test_a_cantilever_on_a_coupled_base(tmp_path, axis, angle, side):
    rot = _rotation(axis, angle)
    r6 = np.kron(np.eye(2), rot)
    k6 = r6 @ LOCAL @ r6.T  # the base turned with the rod: any orientation
    e = rot @ [0.0, 0.0, 1.0]
    load = np.asarray(side, float)
    load = P * (load - (load @ e) * e) / np.linalg.norm(load - (load @ e) * e)
    out = run(tmp_path, _case(rot, k6, load))
    x, x0 = out["result/x"], out["mesh/nodes"]
    r = L * e
    g = np.hstack([np.eye(3), -_cross(r)])
    wrench = np.concatenate([load, np.cross(r, load)])
    closed = g @ np.linalg.solve(k6, wrench) + load * L**3 / (3 * EI)
    base = g @ np.linalg.solve(k6, wrench)
    assert np.linalg.norm(base) > 0.5 * np.linalg.norm(closed)  # the base matters
    tip = x[-1] - x0[-1]
    assert np.linalg.norm(tip - closed) < 1e-3 * np.linalg.norm(closed)
    # all six reaction components: the force and the moment balance the load exactly
    reaction, moment = out["result/reaction"][0], out["result/reaction_moment"][0]
    assert np.allclose(reaction, -load, rtol=0, atol=1e-8 * P)
    arm = x[-1] - x[0]
    assert np.allclose(moment, -np.cross(arm, load), rtol=0, atol=1e-7 * P * L)
    assert np.abs(out["result/reaction"][1:]).max() == 0.0  # the free nodes hold nothing
    # the base's bending moment is the rod's at its foot (it read 0 there)
    across = moment - (moment @ e) * e
    assert out["result/bending_moment"][0] == pytest.approx(np.linalg.norm(across), rel=1e-9)
    assert out["result/curvature"][0] == pytest.approx(np.linalg.norm(across) / EI, rel=1e-9)
    assert out["result/bending_moment"][0] >= out["result/bending_moment"][1:].max()


def test_a_stiff_base_is_the_clamp(tmp_path):
    rot = _rotation([0.0, 1.0, 0.0], 0.4)
    load = P * (rot @ [1.0, 0.0, 0.0])
    stiff = run(tmp_path, _case(rot, 1e9 * np.eye(6), load))["result/x"]
    clamped = _case(rot, np.eye(6), load)
    clamped["supports"] = {"fixed": ["start"], "clamped": ["start"]}
    rigid = run(tmp_path, clamped)
    assert np.max(np.abs(stiff - rigid["result/x"])) < 1e-6 * P * L**3 / (3 * EI)
    assert np.allclose(
        rigid["result/reaction_moment"][0],
        -np.cross(rigid["result/x"][-1] - rigid["result/x"][0], load),
        atol=1e-7 * P * L,
    )


ROD = _case(np.eye(3), LOCAL, np.array([P, 0.0, 0.0]), nodes=11)


@pytest.mark.parametrize(
    "change, says",
    [
        ({"stiffness": [[1.0] * 5] * 6}, "supports.spring[0].stiffness: shape (6, 5)"),
        (
            {"stiffness": (LOCAL + np.triu(np.ones((6, 6)), 1)).tolist()},
            "not symmetric: row 0 column 4 is 2.2, row 4 column 0 1.2:",  # (no np.float64)
        ),
        ({"stiffness": (LOCAL - 5.0 * np.eye(6)).tolist()}, "not positive semidefinite"),
        ({"nodes": [5]}, "supports.spring[0].nodes: node 5 is an interior node of a rod"),
    ],
)
def test_bad_6x6_springs_exit_2(tmp_path, change, says):
    data = {
        **ROD,
        "supports": {"fixed": [], "spring": [{**ROD["supports"]["spring"][0], **change}]},
    }
    case = tmp_path / "case.toml"
    case.write_text(dumps_toml(data))
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "r.h5")])
    assert done.exit_code == 2, done.output
    assert says in done.output
    assert "Traceback" not in done.output


@pytest.mark.parametrize(
    "supports, material, says",
    [
        ({"fixed": ["end"], "clamped": ["start"]}, {}, "is in supports.clamped too"),
        ({"fixed": ["end"], "rotational": [{"nodes": ["start"], "stiffness": 1.0}]}, {},
         "supports.rotational too"),
        ({"fixed": ["start"]}, {}, "node 0 is fixed already"),
        ({"fixed": ["start"]}, {}, "would hold its rotation alone: give that as "
         "[[supports.rotational]]"),  # (it said a spring there would hold nothing)
        ({"fixed": ["end"], "stiffness": COUPLED.tolist()}, {"GJ": 1.0},
         "the end of a rod that twists"),
        ({"fixed": ["end"]}, {"EI": 0.0}, "node 0 is on no edge with EI > 0"),
    ],
)  # fmt: skip
def test_a_6x6_spring_on_no_free_rod_end_exits_2(tmp_path, supports, material, says):
    supports = dict(supports)
    spring = {**ROD["supports"]["spring"][0]}
    if "stiffness" in supports:  # a base coupling the rod's twist with its rocking
        spring["stiffness"] = supports.pop("stiffness")
    data = {
        **ROD,
        "material": {**ROD["material"], **material},
        "supports": {**supports, "spring": [spring]},
    }
    case = tmp_path / "case.toml"
    case.write_text(dumps_toml(data))
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "r.h5")])
    assert done.exit_code == 2, done.output
    assert says in done.output and "supports.spring[0]" in done.output


def test_a_twisting_rod_on_a_base_without_twist_stiffness(tmp_path):
    """GJ > 0 is accepted where the 6x6 holds no twist about the rod's axis."""
    k6 = LOCAL.copy()
    k6[5, :] = k6[:, 5] = 0.0
    data = {**_case(np.eye(3), k6, np.array([P, 0.0, 0.0]), nodes=11)}
    data["material"] = {**data["material"], "GJ": 1.0}
    x = run(tmp_path, data)["result/x"]
    assert x[-1, 0] > 0.0


def test_modes_see_the_base(tmp_path):
    """``catenet modes`` takes the 6x6 into its stiffness: a soft base lowers the first
    bending frequency below the clamped cantilever's, a stiff one gives the clamp's."""
    from catenet import modes
    from catenet.case import build, parse_case

    def first(supports) -> float:
        data = _case(np.eye(3), LOCAL, np.array([P, 0.0, 0.0]), nodes=21)
        data["material"] = {**data["material"], "area": 1e-4, "density": 7850.0}
        data["supports"] = supports
        return float(modes(build(parse_case(data)), 2).frequency[0])

    spring = {"nodes": ["start"]}
    soft = first({"fixed": [], "spring": [{**spring, "stiffness": LOCAL.tolist()}]})
    stiff = first({"fixed": [], "spring": [{**spring, "stiffness": (1e9 * np.eye(6)).tolist()}]})
    clamped = first({"fixed": ["start"], "clamped": ["start"]})
    assert soft < 0.9 * clamped
    assert stiff == pytest.approx(clamped, rel=1e-4)
