"""Dynamic runs with the strands' barrier (solver.self_contact): a strip folded in a U
whose upper layer is thrown onto the lower one lands on it without a single pair of
strands passing through each other, at steps from 1e-3 to 1e-1 s (every straight motion
between two steps checked densely), while without the barrier it passes through; the
capture scene with it on, and its contact phase at steps from 1e-4 to 1e-1 s with no node
in the box and no strands crossing at or between any two steps; off, the runs and the
pattern are those without the key; bad input exits 2 naming the key."""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner
from conftest import small_net
from meshes import folded_strip, strand_crossings

from catenet.case import build, load_case
from catenet.cli import main
from catenet.model.net import Loads, Net
from catenet.solver import path as sv
from catenet.solver.dynamic import solve_dynamic
from catenet.solver.workspace import Workspace
from catenet.terms.rigid_contact import BodyContact
from catenet.terms.strands import SelfContact, default_strand_stiffness

CONFIGS = Path(__file__).parents[2] / "configs" / "contact"


def _fold(dt: float, on: bool, t_end: float = 0.6):
    """The folded strip thrown onto itself (zero gravity, undamped): the frames of every
    step, the net and the term (None when off)."""
    nodes, edges, v0 = folded_strip()
    net = Net.from_arrays(
        nodes, edges, EA=3e3, fixed=[], line_density=3e-3, tension_only=False, flies=True
    )
    dhat = 1e-3
    term = SelfContact(net, kappa=default_strand_stiffness(3e3 * dhat / 0.1, dhat), dhat=dhat)
    ws = Workspace(net, terms=[term] if on else [])
    frames, velocities = [net.nodes.copy()], [v0]

    def keep(k, t, x, v):
        frames.append(x.copy())
        velocities.append(v.copy())

    res = solve_dynamic(
        net, Loads(), dt=dt, damping=0.0, t_end=t_end, workspace=ws, v0=v0,
        stop_at_equilibrium=False, on_step=keep,
    )  # fmt: skip
    assert res.converged and res.time == pytest.approx(t_end)
    return np.array(frames), np.array(velocities), net, term if on else None


def test_without_the_barrier_the_folded_net_passes_through_itself():
    frames, _, net, _ = _fold(0.01, on=False)
    assert len(strand_crossings(frames, net.edges)) > 20


@pytest.mark.parametrize("dt", [0.01, 0.1])
def test_with_it_the_folded_net_never_passes_through_itself(dt):
    frames, v, net, term = _fold(dt, on=True)
    assert strand_crossings(frames, net.edges) == []
    # the layers met: pairs within the activation distance at the end, none touching
    gaps = term.distances(frames[-1])
    assert 0.0 < gaps.min() < term.dhat
    # the barrier is internal: momentum is conserved (no gravity, no damping)
    p = np.einsum("n,tnk->tk", net.mass, v)
    assert np.abs(p - p[0]).max() < 1e-6 * np.abs(p[0]).max()


@pytest.mark.slow
def test_the_folded_net_never_passes_through_itself_at_small_steps():
    frames, _, net, _ = _fold(0.001, on=True)
    assert strand_crossings(frames, net.edges) == []


def test_the_folded_net_example_lands_on_itself_and_through_itself_without(tmp_path):
    case = CONFIGS / "folded_net.toml"
    crossings = {}
    for on in ("true", "false"):
        out = tmp_path / f"{on}.h5"
        args = ["run", str(case), "-o", str(out), "--set", "solver.t_end=0.3"]
        res = CliRunner().invoke(main, [*args, "--set", f"solver.self_contact={on}"])
        assert res.exit_code == 0, res.output
        with h5py.File(out) as f:
            crossings[on] = strand_crossings(f["trajectory/x"][()], f["mesh/edges"][()])
    assert crossings["true"] == [] and len(crossings["false"]) > 20


def test_the_capture_scene_with_self_contact_stays_penetration_free(tmp_path):
    case = CONFIGS / "envisat_capture.toml"
    out = tmp_path / "capture.h5"
    changes = ["solver.t_end=1.45", "solver.self_contact=true", "output.every=1"]
    args = ["run", str(case), "-o", str(out)] + [a for c in changes for a in ("--set", c)]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    assert "first contact at t = 1.3" in res.output
    scene = build(load_case(case, changes))
    assert any(isinstance(t, SelfContact) for t in scene.terms)
    contact = next(t for t in scene.terms if isinstance(t, BodyContact))
    with h5py.File(out) as f:
        x = np.asarray(f["trajectory/x"])
    assert min(contact.gap(xk).min() for xk in x) > 0.0
    assert strand_crossings(x, scene.net.edges) == []


def _body_gaps_between(contact, frames, samples: int = 20) -> np.ndarray:
    """The smallest gap of any net node to the body at each of ``samples`` - 1 states
    between consecutive frames, every node moving straight (the body's four nodes too,
    as the step cap's continuous check assumes)."""
    s = np.linspace(0.0, 1.0, samples + 1)[1:-1]
    pairs = zip(frames[:-1], frames[1:], strict=True)
    return np.array([contact.gap((1.0 - si) * a + si * b).min() for a, b in pairs for si in s])


@pytest.mark.parametrize("dt, t_end", [(1e-4, 0.02), (1e-3, 0.06), (1e-2, 0.4), (1e-1, 1.0)])
def test_the_capture_never_has_a_node_in_the_box_nor_strands_crossing_at_any_step(dt, t_end):
    """The capture scene with self-contact on, its box moved up to 3 cm below the net
    (the net meets it at once: the contact phase, not the 1.3 s of flight before it),
    at steps from 1e-4 to 1e-1 s: the nodes enter the barrier's reach (the net lands
    and, at the longer steps, wraps over the box's top), and at every step and at 19
    states between each two (linear interpolation of all positions, as the continuous
    checks assume) no net node is inside the body and no two strands that share no
    node cross or touch (``strand_crossings``: 50 samples and bisection per interval)."""
    changes = [
        "solver.self_contact=true", f"solver.dt={dt}", f"solver.t_end={t_end}",
        "obstacle.0.center=[0.0, 0.0, 2.97]",
    ]  # fmt: skip
    scene = build(load_case(CONFIGS / "envisat_capture.toml", changes))
    assert any(isinstance(t, SelfContact) for t in scene.terms)
    contact = next(t for t in scene.terms if type(t) is BodyContact)
    settings = sv.Settings.of(scene.case.solver)
    frames = [scene.net.nodes.copy()]
    res = sv.solve(scene, settings, on_step=lambda step: frames.append(step.x.copy()))
    assert res.converged and res.time == pytest.approx(t_end)
    frames = np.array(frames)
    assert len(frames) > t_end / dt  # every step kept (a few cut ones too)
    at_steps = np.array([contact.gap(x).min() for x in frames])
    assert at_steps[0] == pytest.approx(0.03) and at_steps.min() < contact.dhat
    assert at_steps.min() > 0.0 and _body_gaps_between(contact, frames).min() > 0.0
    assert strand_crossings(frames, scene.net.edges) == []


def test_off_the_scene_and_its_pattern_are_those_without_the_key():
    case = CONFIGS / "tether_capture.toml"
    plain = build(load_case(case, ["solver.t_end=0.05"]))
    off = build(load_case(case, ["solver.t_end=0.05", "solver.self_contact=false"]))
    on = build(load_case(case, ["solver.t_end=0.05", "solver.self_contact=true"]))
    assert [type(t) for t in off.terms] == [type(t) for t in plain.terms]
    assert not any(isinstance(t, SelfContact) for t in plain.terms)
    settings = sv.Settings.of(plain.case.solver)
    ws_plain, ws_off = sv.workspace(plain, settings), sv.workspace(off, settings)
    assert ws_off.system.nnz == ws_plain.system.nnz
    assert sv.workspace(on, settings).system.nnz >= ws_plain.system.nnz
    a = sv.solve(plain, settings, workspace=ws_plain)
    b = sv.solve(off, settings, workspace=ws_off)
    assert np.array_equal(a.x, b.x) and a.iterations == b.iterations


@pytest.mark.parametrize(
    "change, message",
    [
        ('self_contact = "yes"', "solver.self_contact = 'yes': must be true or false"),
        ("self_contact = 1", "solver.self_contact = 1: must be true or false"),
        (
            "self_contact = true\nself_contact_distance = -0.01",
            "solver.self_contact_distance = -0.01",
        ),
        (
            "self_contact = true\nmethod = 'static'",
            "solver.self_contact = true: is for dynamic runs",
        ),
    ],
)
def test_bad_self_contact_input_exits_2_naming_the_key(write_case, tmp_path, change, message):
    text = small_net(t_end=0.05).replace("[solver]\n", "[solver]\n" + change + "\n")
    if "method = 'static'" in change:
        text = text.replace('method = "dynamic"\n', "")
    res = CliRunner().invoke(main, ["run", str(write_case(text)), "-o", str(tmp_path / "o.h5")])
    assert res.exit_code == 2, res.output
    assert message in res.output and "Traceback" not in res.output


CROSSING = """
title = "two steel wires crossing, the upper one pressed onto the lower"
[geometry]
kind = "graph"
nodes = [[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.002], [0.0, 1.0, 0.002]]
fixed = [0, 1, 2, 3]
[[geometry.cable]]
name = "lower"
nodes = [0, 1]
edge_length = 0.0513
[[geometry.cable]]
name = "upper"
nodes = [2, 3]
edge_length = 0.05
[material]
E = 2.0e11
radius = 0.003
density = 7850.0
[[load.point]]
cable = "upper"
at = 0.5
force = [0.0, 0.0, -1000.0]
[solver]
method = "dynamic"
self_contact = true
"""


def test_crossing_wires_run_to_rest_with_self_contact(tmp_path):
    """Run to rest (the default without t_end), the strands' pattern grows as the wires
    meet; the continuation stages of the run to rest were views of the pattern before
    it grew, and the run stopped with an internal error ("the pattern grew since the
    system was built"). Now at rest: the lower wire carries the contact force alone, its
    supports' reactions equal to it."""
    case = tmp_path / "crossing.toml"
    case.write_text(CROSSING)
    out = tmp_path / "c.h5"
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(out)])
    assert done.exit_code == 0, done.output
    with h5py.File(out) as h5:
        reaction = h5["result/reaction"][:]
    lower = reaction[[0, 1], 2].sum()  # the lower wire's ends
    assert 400.0 < lower < 600.0  # its share of the 1 kN by the wires' stiffnesses
    assert reaction[:, 2].sum() == pytest.approx(1000.0, rel=1e-6)
