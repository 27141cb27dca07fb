"""A moving obstacle that carries the net onto a fixed one pinches it as two moving jaws
do (``catenet.terms.pinch.pinch_note``, its carrier moved on by a planned step against
the fixed obstacle). Found on a newcomer's model: a blade dragging a 6 mm cord round a
fixed post, driven to 2 mm from it (the cord needs 6 mm), stopped with advice on dt,
max_iter and the post's activation distance; following either changed nothing."""

from __future__ import annotations

import pytest
from click.testing import CliRunner
from contact_cases import dragged_cord

from catenet.cli import main


def _run(tmp_path, history: str):
    case = tmp_path / "cord.toml"
    text = dragged_cord(
        nodes=41,
        box=(0.0, -0.03),
        half=(0.01, 0.02, 0.3),
        history=history,
        post=(0.0, 0.15),
        t_end=0.4,
        post_half=0.3,
    )
    case.write_text(text)
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
