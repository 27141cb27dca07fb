"""A contact barrier's stiffness in the residual's round-off floor (``Term.stiff_roundoff``).
A barrier holding a node at a gap far below its activation distance is stiff, its force
over its gap, and turns the positions' round-off (eps |x|) into force round-off far above
eps times the forces that meet there, the floor the convergence test knew. A cord wrapped
round a paddle's corners at a gap of 0.36 nm kept residuals of 1e-8 N at those two nodes
where their floor was 2e-9 N, so its steps were called stagnated and the run failed; the
barrier's share puts that floor at 1e-7 to 1e-6 N."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from catenet.cli import main
from catenet.solver.potential import FLOOR_SAFETY
from catenet.terms.contact import PlaneBarrier
from catenet.terms.segments import EdgeContact

EPS = np.finfo(float).eps


def test_a_plane_barriers_floor_covers_its_force_over_a_few_ulps_of_position():
    """A node 1 nm above a plane at z = 100 m (kappa 1e3 N/m, dhat 1 mm): its barrier
    force's spread over positions a few ulps apart is within the floor's share, which is
    the barrier's stiffness times the coordinates' size (far above eps times its force);
    beyond dhat the barrier adds none."""
    term = PlaneBarrier([0], [0.0, 0.0, 100.0], [0.0, 0.0, 1.0], kappa=1e3, dhat=1e-3)
    assert term.barrier
    x = np.array([[0.1, 0.2, 100.0 + 1e-9]])
    grad = np.zeros_like(x)
    term.gradient(x, grad)
    level = term.stiff_roundoff(x)
    assert level is not None and level.shape == (1,)
    force = abs(grad[0, 2])
    spread = 0.0
    for k in range(-4, 5):
        moved = x.copy()
        moved[0, 2] = x[0, 2] + k * np.spacing(x[0, 2])
        g = np.zeros_like(x)
        term.gradient(moved, g)
        spread = max(spread, abs(g[0, 2] - grad[0, 2]))
    assert spread > 1e3 * EPS * force  # the position's round-off, not the force's
    assert spread <= FLOOR_SAFETY * EPS * level[0]
    values = np.zeros(9)
    term.hessian(x, values)
    assert level[0] == np.abs(values[8]) * (x[0, 2] + 100.0)  # k_zz (|z| + |p|)
    far = np.array([[0.1, 0.2, 100.01]])
    assert term.stiff_roundoff(far) is None


def test_the_edges_barrier_gives_its_floor_on_the_edges_nodes_only():
    """An edge of a rope 0.36 nm beyond its 3 mm radius from a solid's edge: the floor's
    share falls on the edge's two nodes, none on a node elsewhere."""
    r, gap = 0.003, 3.6e-10
    points = np.array([[-0.01, -0.005, r + gap], [-0.01, 0.005, r + gap]])
    edges = np.array([[0, 1], [1, 2]])
    term = EdgeContact(edges, [0.02, 0.3], points, [[0, 1]], 0.0, r=r, kappa=1e2, dhat=2e-6,
                       n_nodes=3)  # fmt: skip
    x = np.array([[-0.02, 0.0, 0.0], [0.0, 0.0, 0.0], [0.3, 0.0, 0.0]])
    level = term.stiff_roundoff(x)
    assert level is not None
    assert level[0] > 0.0 and level[1] > 0.0 and level[2] == 0.0


PADDLE_ON_A_BELT = """
title = "a paddle pushing a cord across a belt"

[geometry]
kind = "cable"
start = [-1.0, 0.0, 0.0035]
end = [1.0, 0.0, 0.0035]
nodes = 101

[material]
EA = 5.0e4
radius = 0.003
density = 1140.0
prestress = 50.0

[load]
gravity = [0.0, 0.0, -9.81]

[[obstacle]]
kind = "box"
center = [0.0, 0.0, -0.05]
half_size = [2.0, 2.0, 0.05]
velocity = [0.0, 0.3, 0.0]
friction = 0.3

[[obstacle]]
kind = "box"
center = [0.0, -0.05, 0.0402]
half_size = [0.1, 0.01, 0.04]
velocity = [0.0, 0.5, 0.0]
history = [[0.0, 1.0], [0.3, 1.0], [0.35, 0.0], [1.0, 0.0]]

[solver]
method = "dynamic"
integrator = "bdf2"
dt = 0.005
t_end = 0.4
edge_contact = true
"""


@pytest.mark.roundoff  # the round-off floor's verdict: perturbed, two threads too
def test_a_paddle_pushing_a_cord_across_a_belt_runs_to_its_end(tmp_path):
    """A newcomer's case: a 6 mm cord (EA 50 kN, 50 N prestress, pinned ends) lying on a
    belt that runs across it, pushed by a paddle 0.2 m wide at 0.5 m/s that stops at
    0.35 s, 0.2 mm above the belt. It stopped at t = 0.165 s ("no convergence", its steps
    11x shorter than dt): the nodes in front of the paddle started each step twice its
    travel ahead (``Moving._predicted``), the edges sliding round the paddle's corners at
    0.36 nm capped every Newton step at a quarter (``plane_time``), and the residual at
    the corners' round-off was called stagnated (the barrier's floor). Now it runs to its
    end; the cord, held round the stopped paddle, has the tension of its stretched
    length."""
    import h5py

    case = tmp_path / "paddle.toml"
    case.write_text(PADDLE_ON_A_BELT)
    out = tmp_path / "r.h5"
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(out)])
    assert done.exit_code == 0, done.output
    with h5py.File(out) as f:
        x = f["trajectory/x"][-1]
        tension = f["trajectory/tension"][-1]
        assert f["trajectory/time"][-1] == 0.4
    stretched = np.linalg.norm(np.diff(x, axis=0), axis=1).sum()  # the cord's length
    # EA (L / L0 - 1) + the prestress's strain at the start: L0 = 2 m / (1 + 50 / EA)
    hand = 5.0e4 * (stretched * (1.0 + 50.0 / 5.0e4) / 2.0 - 1.0)
    assert abs(tension.max() - hand) < 0.01 * hand
    assert x[50, 1] > 0.12  # carried 0.125 m by the paddle, its face at y = 0.115 m + r
