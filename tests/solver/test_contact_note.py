"""A dynamic run that fails because Newton's steps keep being cut short at one obstacle's
contact says so (``NewtonResult.contact_note``): the obstacle, its barrier's activation
distance and the key that lengthens it. A barrier far narrower than the motion Newton's
steps want (1e-4 of an edge by default, microns on a cord) is approached a share of the
way per iteration, so a step's iterations run out. Found on a newcomer's model: a 6 mm
nylon cord dragged round a post by a moving box, edge contact on, failed with "its steps
stay about 7x shorter than dt" and advice on dt, max_iter and stiffness only; 100x the
default distance on both obstacles ran it to its end (81 nodes: 307 steps, the largest
tension 1986.59 N, as with 40x)."""

from __future__ import annotations

from click.testing import CliRunner
from contact_cases import dragged_cord

from catenet.cli import main
from catenet.solver.newton import NewtonResult
from catenet.terms import Term

CORD = dragged_cord(
    nodes=21,
    box=(0.6, -0.045),
    half=(0.03, 0.015, 0.1),
    history=[[0.0, 1.0], [0.3, 1.0], [0.35, 0.0], [0.5, 0.0]],
    post=(0.3, 0.035),
    t_end=0.1,
    gravity=True,
)


def _run(tmp_path, *sets):
    case = tmp_path / "cord.toml"
    case.write_text(CORD)
    args = ["run", str(case), "-o", str(tmp_path / "r.h5")]
    for item in sets:
        args += ["--set", item]
    return CliRunner().invoke(main, args)


def _tension(output: str) -> float:
    line = next(row for row in output.splitlines() if row.startswith("max tension"))
    return float(line.split()[2])


def test_steps_cut_short_at_an_obstacle_name_it_and_its_distance_and_the_advice_works(tmp_path):
    """With 5 Newton iterations a step (the box meets the cord at t = 0.054 s), the run
    fails naming the box and 100x its distance (1e-5 m: 1e-4 of the 0.1 m edges); with
    that, it fails later at the post and names the post; with both, it runs, and its
    largest tension is within 0.5 % of the default distance's where 8 iterations a step
    converge (88.55 against 88.77 N)."""
    few = "solver.max_iter=5"
    first = _run(tmp_path, few)
    assert first.exit_code == 1, first.output
    text = " ".join(first.output.split())
    assert "Newton iterations were cut short where a full step would have reached " in text
    assert "obstacle[0] (kind 'box'), whose barrier acts within 9.99e-06 m" in text, text
    assert "(e.g. obstacle[0].distance = 0.000999, 100x;" in text, text
    box = "obstacle[0].distance=0.000999"
    second = _run(tmp_path, few, box)
    assert second.exit_code == 1, second.output
    text = " ".join(second.output.split())
    assert "reached obstacle[1] (kind 'capsule')" in text, text
    assert "(e.g. obstacle[1].distance = 0.000999, 100x;" in text, text
    both = _run(tmp_path, few, box, "obstacle[1].distance=0.000999")
    assert both.exit_code == 0, both.output
    exact = _run(tmp_path, "solver.max_iter=8")
    assert exact.exit_code == 0, exact.output
    assert abs(_tension(both.output) / _tension(exact.output) - 1.0) < 5e-3


class _Obstacle(Term):
    label = "obstacle[2] (kind 'plane')"
    key = "obstacle[2].distance"
    dhat = 1e-4


class _Unkeyed(Term):
    label = "obstacle[2] (kind 'plane')"  # a continuation's stage: a label, no key
    dhat = 1e-2


def test_the_note_needs_most_iterations_cut_short_at_one_obstacle_with_a_distance_key():
    """Half the iterations or more at one obstacle, its nodes' and edges' barriers counted
    together: the note, with its key; fewer, a converged solve, or terms without a key (a
    continuation's wider stages, self-contact): none."""
    nodes, edges, unkeyed = _Obstacle(), _Obstacle(), _Unkeyed()
    note = NewtonResult(False, 10, 1.0, 1e-6, capped={unkeyed: 5, nodes: 3, edges: 2})
    text = note.contact_note()
    assert text.startswith("; 5 of its 10 Newton iterations were cut short"), text
    assert "reached obstacle[2] (kind 'plane'), whose barrier acts within 0.0001 m" in text
    assert "(e.g. obstacle[2].distance = 0.01, 100x;" in text, text
    assert NewtonResult(False, 10, 1.0, 1e-6, capped={nodes: 4}).contact_note() == ""
    assert NewtonResult(True, 10, 1e-7, 1e-6, capped={nodes: 9}).contact_note() == ""
    assert NewtonResult(False, 10, 1.0, 1e-6, capped={unkeyed: 9}).contact_note() == ""
