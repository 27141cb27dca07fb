"""A moving obstacle that carries the net onto a fixed one pinches it as two moving jaws
do (``catenet.terms.pinch.pinch_note``, its carrier moved on by a planned step against
the fixed obstacle). Found on a newcomer's model: a blade dragging a 6 mm cord round a
fixed post, driven to 2 mm from it (the cord needs 6 mm), stopped with advice on dt,
max_iter and the post's activation distance; following either changed nothing."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from catenet.cli import main

CORD = """
[geometry]
kind = "cable"
start = [-1.0, 0.0, 0.0]
end = [1.0, 0.0, 0.0]
nodes = 41

[material]
E = 2.5e9
radius = 0.003
density = 1140.0
prestress = 50.0

[[obstacle]]
kind = "box"
center = [0.0, -0.03, 0.0]
half_size = [0.01, 0.02, 0.3]
velocity = [0.0, 0.5, 0.0]
history = HISTORY

[[obstacle]]
kind = "capsule"
start = [0.0, 0.15, -0.3]
end = [0.0, 0.15, 0.3]
radius = 0.02

[solver]
method = "dynamic"
dt = 0.002
t_end = 0.4
edge_contact = true
"""


def _run(tmp_path, history: str):
    case = tmp_path / "cord.toml"
    case.write_text(CORD.replace("HISTORY", history))
    return CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "r.h5")])


@pytest.mark.roundoff
def test_a_blade_driven_against_a_fixed_post_pinches_the_cord_and_says_so(tmp_path):
    """The blade's face stops 2 mm from the post: the run stops naming both obstacles and
    the edge between them, not the distance or the step. Stopped 10 mm from it, the cord
    (6 mm) fits and the run ends with it wrapped round the post, its tension that of the
    path round blade and post (592.9 N)."""
    done = _run(tmp_path, "[[0.0, 0.0], [0.05, 1.0], [0.276, 1.0], [0.326, 0.0]]")
    assert done.exit_code == 1, done.output
    text = " ".join(done.output.split())
    assert "obstacle[0] (kind 'box') and obstacle[1] (kind 'capsule') pinch the edge" in text
    assert "must not close on the net against another" in text, text
    assert "obstacle[1].distance =" not in text, text  # no advice that cannot help
    fits = _run(tmp_path, "[[0.0, 0.0], [0.05, 1.0], [0.26, 1.0], [0.31, 0.0]]")
    assert fits.exit_code == 0, fits.output
    assert "max tension  592.9" in fits.output, fits.output
