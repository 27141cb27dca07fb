"""A structure whose loads compress members across a mechanism never ends converged
(``catenet.solver.stability.PathJudge._pushed``, rule 6's first-order case;
``catenet.solver.mechanism.compressed_across`` and ``finite``).

A three-hinged arch of two bilateral bars (10 m span, pinned feet, a 10 kN load at its
crown) whose crown nothing holds across its plane: unloaded, the crown's move across
the plane has no stiffness and stretches no bar to second order (a mechanism); loaded,
the bars are compressed and push it that way (a negative stiffness -2N/l), so the arch
that carries the load is unstable from its first newton. Newton's solve found the bars
hanging as a V below the supports (each turned through 43.6 degrees, under rule 5's
45), stable, and the run said "converged", exit 0. Now a collapse at load factor 0 from
every start, in three unit systems, for arches from flat to steep, at loads from 1e-11
of EA to far beyond the arch's own snap-through load, pushed across its plane or not,
beside a sagging rope, the start kept. Held across its plane by a roller it stands (the
crown's drop to 1e-7 of its closed form); the same bars given hanging carry the load; a
bilateral rope hung off the vertical, whose lower part the load compresses across its
sway, is no mechanism (its uniform self-stress holds every sway at second order) and
converges.

Marked ``roundoff``: `make test` runs these again with every node moved by 1e-12 of the
net's size and two threads.
"""

from __future__ import annotations

import math

import h5py
import numpy as np
import pytest
import tomli_w
from click.testing import CliRunner

import catenet
from catenet.case import build, parse_case
from catenet.cli import main
from catenet.solver.stability import CollapseError

pytestmark = pytest.mark.roundoff

UNITS = {"SI": (1.0, 1.0), "kN-m": (1.0, 1e-3), "N-mm": (1e3, 1.0)}  # length, force
FIRST = "the structure is a mechanism under these loads: at load factor 0 it has a mode"


def arch(
    units: str = "SI",
    *,
    rise: float = 2.0,
    load: float = 1e4,
    EA: float = 1e8,
    seed: int = 0,
    held: bool = False,
    hanging: bool = False,
    lateral: float = 0.0,
) -> dict:
    """The arch: nodes 0 and 2 its pinned feet 10 m apart, node 1 its crown ``rise`` above
    them (below, ``hanging``), ``load`` [N] down on the crown; ``held``: a roller holds the
    crown across the plane; ``seed``: its nodes moved by up to 1e-9 of the span;
    ``lateral``: a push across the plane at the crown, that share of the load."""
    m, n = UNITS[units]
    nodes = np.array([[0.0, 0.0, 0.0], [5.0, 0.0, -rise if hanging else rise], [10.0, 0.0, 0.0]])
    if seed:
        nodes += 1e-8 * np.random.default_rng(seed).uniform(-1.0, 1.0, nodes.shape)
    supports: dict = {"fixed": [0, 2]}
    if held:
        supports["roller"] = [{"nodes": [1], "normal": [0.0, 1.0, 0.0]}]
    return {
        "title": "a three-hinged arch",
        "units": units,
        "geometry": {
            "kind": "graph",
            "nodes": (m * nodes).tolist(),
            "edges": [[0, 1], [1, 2]],
            "EA": [n * EA] * 2,
            "tension_only": [False, False],
        },
        "supports": supports,
        "load": {"point": [{"node": 1, "force": [0.0, n * lateral * load, -n * load]}]},
    }


def run(tmp_path, case: dict):
    path = tmp_path / "arch.toml"
    path.write_bytes(tomli_w.dumps(case).encode())
    out = tmp_path / "arch.h5"
    return CliRunner().invoke(main, ["run", str(path), "-o", str(out), "-q"]), out


@pytest.mark.parametrize("units", list(UNITS))
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_an_arch_free_across_its_plane_collapses_at_the_first_load(tmp_path, units, seed):
    result, out = run(tmp_path, arch(units, seed=seed))
    assert result.exit_code == 1, result.output
    assert "the load path collapses beyond load factor 0:" in result.output, result.output
    assert FIRST in result.output, result.output
    with h5py.File(out, "r") as f:
        assert str(f["result"].attrs["stability"]) == "collapsed"
        assert not f["result"].attrs["converged"]
        moved = np.linalg.norm(f["result/x"][:] - f["mesh/nodes"][:], axis=1)
    assert moved.max() < 1e-6 * UNITS[units][0]  # the start kept, not the hanging V


@pytest.mark.parametrize(
    ("rise", "load", "EA"),
    [
        (0.3, 1e3, 1e6), (0.3, 1e5, 1e6), (0.5, 1e3, 1e8), (1.0, 1e4, 1e6), (2.0, 1e4, 1e6),
        (4.0, 1e5, 1e6), (2.0, 1e-3, 1e8),
    ],
)  # fmt: skip
def test_flat_to_steep_arches_collapse_at_any_load(rise, load, EA):
    """From a flat arch at 12 and 1200 times the load at which its bars would snap
    through in their plane (0.385 EA (rise / l)^3) to a steep one, and under a load of
    1e-11 of EA: the load path collapses at load factor 0, never ends hanging."""
    scene = build(parse_case(arch(rise=rise, load=load, EA=EA)))
    with pytest.raises(CollapseError) as collapsed:
        catenet.solve(scene, catenet.Settings.of(scene.case.solver))
    assert collapsed.value.factor == 0.0
    assert FIRST in str(collapsed.value) or "unstable" in str(collapsed.value)


@pytest.mark.parametrize("lateral", [1e-4, 2e-3, 1e-2])
def test_a_push_across_its_plane_fells_the_arch_too(lateral):
    """The crown also pushed across the plane (a share of the load that drives the mode
    sideways): the arch falls over sideways, a collapse at load factor 0 (a 1 % push
    ended hanging, "converged", also after the first-order rule came in, while that
    rule read only modes the loads left alone)."""
    scene = build(parse_case(arch(lateral=lateral)))
    with pytest.raises(CollapseError) as collapsed:
        catenet.solve(scene, catenet.Settings.of(scene.case.solver))
    assert collapsed.value.factor == 0.0


def test_an_arch_beside_a_sagging_rope_collapses():
    """The same arch beside a separate bilateral rope whose own load sags it (a mode the
    loads move, which the rope's tension holds): the arch still falls over."""
    case = arch()
    geometry = case["geometry"]
    geometry["nodes"] += [[0.0, 5.0, 0.0], [10.0, 5.0, 0.0]]
    geometry["edges"] += [[3, 4]]
    geometry["EA"] += [1e6]
    geometry["tension_only"] += [False]
    case["supports"]["fixed"] += [3, 4]
    case["load"]["point"].append({"node": 3, "force": [0.0, 0.0, 0.0]})
    scene = build(parse_case(case))
    with pytest.raises(CollapseError) as collapsed:
        catenet.solve(scene, catenet.Settings.of(scene.case.solver))
    assert collapsed.value.factor == 0.0


@pytest.mark.parametrize("units", list(UNITS))
def test_held_across_its_plane_the_arch_stands(tmp_path, units):
    """A roller across the plane at the crown: converged, stable, the crown's drop d that
    balances the load with the bars' forces, 2 EA (l - l0) / l0 (h - d) / l = -P with
    l = hypot(5, h - d), to 1e-7 (P l0 / (2 EA sin^2 theta) to first order)."""
    from scipy.optimize import brentq

    result, out = run(tmp_path, arch(units, held=True))
    assert result.exit_code == 0, result.output
    m = UNITS[units][0]
    with h5py.File(out, "r") as f:
        assert str(f["result"].attrs["stability"]) == "stable"
        drop = f["mesh/nodes"][1, 2] - f["result/x"][1, 2]
    rise, load, EA = 2.0, 1e4, 1e8
    l0 = math.hypot(5.0, rise)

    def out_of_balance(d: float) -> float:
        length = math.hypot(5.0, rise - d)
        return 2.0 * EA * (length - l0) / l0 * (rise - d) / length + load

    expected = brentq(out_of_balance, 0.0, 0.5 * rise, xtol=1e-15)
    assert drop / m == pytest.approx(expected, rel=1e-7)


def test_the_same_bars_hung_as_a_v_carry_the_load(tmp_path):
    result, out = run(tmp_path, arch(hanging=True))
    assert result.exit_code == 0, result.output
    with h5py.File(out, "r") as f:
        assert str(f["result"].attrs["stability"]) == "stable"
        tension = f["result/tension"][:]
    assert tension == pytest.approx(1e4 * math.hypot(5.0, 2.0) / 4.0, rel=1e-3)


@pytest.mark.parametrize(
    ("E", "off"),
    [(1e7, 3e-5), (1e7, 1e-4), (1e7, 0.002), (1e7, 0.05), (2.1e11, 3e-5), (2.1e11, 0.05)],
)
def test_a_rope_hung_off_the_vertical_bulges_into_tension(E, off):
    """A bilateral rope (10 m, 20 edges) between supports ``off`` [m] off the vertical,
    given straight at its rest length, nylon-soft or steel-stiff: its weight compresses
    its lower part across its zero modes, but those modes stretch its edges at second
    order against the straight rope's uniform self-stress (no mechanism: ``finite``
    leaves them out), and the rope bulges close by (a soft one into a loop whose lowest
    edge stands on the support): converged, stable, from round-off's starts too (0.1 mm
    off the vertical collapsed when the rule read every mode)."""
    case = {
        "title": "a rope hung off the vertical",
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [off, 0, 10], "nodes": 21},
        "material": {"E": E, "radius": 0.005, "density": 1140.0, "tension_only": False},
        "load": {"gravity": [0.0, 0.0, -9.81]},
    }
    scene = build(parse_case(case))
    result = catenet.solve(scene, catenet.Settings.of(scene.case.solver))
    assert result.converged
    assert result.stability == "stable"


def test_a_mechanism_moves_where_no_self_stress_holds_it():
    """``finite``: the arch's crown across its plane moves as a mechanism (no
    self-stress); every sway of a straight rope's nodes stretches it against its uniform
    self-stress (none moves), as it does with its nodes moved by 1e-9 of its length."""
    from catenet.solver.mechanism import finite, zero_modes
    from catenet.solver.stability import SOFT
    from catenet.solver.tangent import _scale
    from catenet.solver.workspace import Workspace

    rope = {
        "title": "a straight rope",
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [0.0001, 0, 10], "nodes": 11},
        "material": {"EA": 1e6, "tension_only": False},
    }
    for case, moving in [(arch(), 1), (rope, 0)]:
        scene = build(parse_case(case))
        ws = Workspace(scene.net)
        for shift in (0.0, 1e-9):
            x = scene.net.nodes + shift * np.random.default_rng(1).uniform(
                -10, 10, (scene.net.n_nodes, 3)
            )
            x[scene.net.fixed] = scene.net.nodes[scene.net.fixed]
            modes = zero_modes(ws.system, x, _scale(ws.system), SOFT, None)
            assert modes.shape[1] >= 1
            assert finite(ws.system, modes, x).shape[1] == moving


def test_the_first_order_test_reads_the_mechanism_only():
    """``compressed_across``: the arch's compressed bars give its crown's move across the
    plane a stiffness of about -2.7 times its load per bar length; a string pulled across
    gets 0: its sway is no mechanism (its own sag holds it)."""
    from catenet.solver.mechanism import compressed_across, zero_modes
    from catenet.solver.stability import SOFT
    from catenet.solver.tangent import _scale
    from catenet.solver.workspace import Workspace

    for case, expected in [(arch(), -2.69), (arch(rise=0.0), 0.0)]:
        scene = build(parse_case(case))
        ws = Workspace(scene.net)
        system, x = ws.system, scene.net.nodes.copy()
        modes = zero_modes(system, x, _scale(system), SOFT, None)  # (round-off: 1e-12 moves)
        assert modes.shape[1] >= 1
        g = ws.potential(scene.loads, 1.0).evaluate(x).g.copy()
        value = compressed_across(system, modes, x, g, load=1e4)
        assert value == pytest.approx(expected, abs=0.01)


def test_an_arch_tied_to_the_middle_of_its_feet_collapses():
    """A tension-only tie at its rest length from the crown to a support midway between
    the feet: the arch's turn about the line through its feet keeps the tie's length, a
    mechanism still. A self-stress that the test found only in round-off (its sum
    -2.8e-17 against terms of 0.23) called it held, and the arch ended as the V,
    "converged"; the tie, slack, holds nothing."""
    case = arch()
    geometry = case["geometry"]
    geometry["nodes"] += [[5.0, 0.0, 0.0]]
    geometry["edges"] += [[1, 3]]
    geometry["EA"] += [1e6]
    geometry["tension_only"] += [True]
    case["supports"]["fixed"] += [3]
    scene = build(parse_case(case))
    with pytest.raises(CollapseError) as collapsed:
        catenet.solve(scene, catenet.Settings.of(scene.case.solver))
    assert collapsed.value.factor == 0.0


@pytest.mark.parametrize("off", [0.002, 0.05])
def test_a_rope_on_a_roller_at_its_top_converges(off):
    """The rope hung off the vertical with its top on a roller that holds it along the
    rope: the roller's reaction balances the rope's uniform self-stress, which holds every
    sway (the held direction left in the compatibility matrix dropped it, and the rope
    collapsed)."""
    case = {
        "title": "a rope on a roller",
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [off, 0, 10], "nodes": 21},
        "material": {"E": 1e7, "radius": 0.005, "density": 1140.0, "tension_only": False},
        "supports": {"fixed": [0], "roller": [{"nodes": [20], "normal": [off / 10, 0, 1]}]},
        "load": {"gravity": [0.0, 0.0, -9.81]},
    }
    scene = build(parse_case(case))
    result = catenet.solve(scene, catenet.Settings.of(scene.case.solver))
    assert result.converged and result.stability == "stable"
