"""Fast subset of the numerical-stability stress test (``tests/stress_matrix.py``).

Every scene must end in a right answer: a converged state that passes its check (Eq. 17,
the exact discrete chain, equilibrium recomputed from the answer, static = dynamic) or a
clear catenet error where that is right; never another exception, never a NaN. No timing
assertions. The full matrix runs with ``python -m benchmarks stress``.
"""

from __future__ import annotations

import pytest
import stress_matrix as stress
from scenes import equilibrium_error, midpoint_cable


def _params():
    for scene in stress.scenes(quick=True):
        yield pytest.param(scene, id=scene.id)


@pytest.fixture(scope="module", autouse=True)
def _one_thread():
    from catenet.solver.threads import set_threads

    set_threads(1)


@pytest.mark.parametrize("scene", list(_params()))
def test_scene_gives_a_right_answer(scene):
    row = stress.run_scene(scene)
    assert not row["status"].startswith("BUG"), row
    assert row["status"] != "NaN in result", row
    assert row["passed"], row


def test_quick_subset_covers_every_group():
    groups = {s.group for s in stress.scenes(quick=False)}
    assert {s.group for s in stress.scenes(quick=True)} == groups


def test_equilibrium_error_sees_a_wrong_state():
    """The check is not vacuous: a state moved off the equilibrium fails it."""
    from catenet.solver.static import solve_static

    net, loads, mid = midpoint_cable(10.0, nodes=11)
    res = solve_static(net, loads)
    assert equilibrium_error(net, loads, res) < 1e-8
    res.x[mid, 2] *= 1.01
    assert equilibrium_error(net, loads, res) > 1e-4
