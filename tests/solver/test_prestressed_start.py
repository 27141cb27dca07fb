"""A prestressed net with obstacles is solved directly first (``start.direct_solve``):
its tension holds its rotations, so Newton's model holds without the stiffness
continuation, whose soft stages scale the prestress with EA and let the net sag
onto obstacles it never reaches. Found on a newcomer's model: a 12 mm nylon rope (200 N
prestress) lifted by a bar 20 mm below it, from its static equilibrium at t = 0: at
EA x 3.7e-4 the rope sagged about 0.3 m onto the bar, and the start took 35 703 Newton
iterations and 102 s for a sag of 6.94 mm that never touches the bar."""

from __future__ import annotations

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.cli import main

ROPE = """
[geometry]
kind = "cable"
start = [-1.5, 0.0, 0.0]
end = [1.5, 0.0, 0.0]
nodes = 61

[material]
E = 3.0e9
radius = 0.006
density = 1140.0
prestress = 200.0

[load]
gravity = [0.0, 0.0, -9.81]

[[obstacle]]
kind = "capsule"
start = [0.0, -0.3, -0.045]
end = [0.0, 0.3, -0.045]
radius = 0.025
velocity = [0.0, 0.0, 0.5]
history = [[0.0, 1.0], [0.2, 1.0], [0.25, 0.0], [0.5, 0.0]]

[solver]
method = "dynamic"
dt = 0.002
t_end = 0.002
edge_contact = true
initial_state = "equilibrium"
"""


@pytest.mark.roundoff
def test_a_prestressed_rope_over_a_bar_starts_from_its_equilibrium_solved_directly(tmp_path):
    """The start's static solve takes a handful of Newton iterations (the direct solve,
    no stiffness stage) and gives the hand sag w L^2 / (8 H) of the rope under its
    tension (6.948 mm, H the 204.85 N the summary gives; within 0.5 %: the parabola and
    the stretch), the rope clear of the bar."""
    case = tmp_path / "rope.toml"
    case.write_text(ROPE)
    out = tmp_path / "r.h5"
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(out), "-v"])
    assert done.exit_code == 0, done.output[-2000:]
    newton = [line for line in done.output.splitlines() if "catenet.solver.newton: static" in line]
    assert 0 < len(newton) <= 10, len(newton)
    assert all("static (direct)" in line for line in newton), newton[:3]
    with h5py.File(out) as f:
        x0 = f["trajectory/x"][0]
        tension = float(np.max(f["result/tension"][()]))
    w = 1140.0 * np.pi * 0.006**2 * 9.81
    sag = -float(x0[30, 2])
    assert abs(sag / (w * 3.0**2 / (8.0 * tension)) - 1.0) < 5e-3, (sag, tension)
    assert float(np.min(x0[:, 2])) > -0.02 + 0.006  # the bar's top, less the rope's radius


def test_a_direct_solve_that_does_not_converge_falls_back_to_the_continuation(
    tmp_path, monkeypatch
):
    """The rope over a fixed bar, a static run: with the direct solve held to one Newton
    iteration it cannot converge, and the solve goes on from the given state through the
    continuation (its stages in the log, the direct iteration counted with them) to the
    same equilibrium (the sag to 1e-9 m of the direct one's)."""
    from catenet.solver import start

    static = ROPE.split("velocity")[0] + "\n[solver]\nedge_contact = true\n"
    case = tmp_path / "rope.toml"
    case.write_text(static)
    sags = []
    for limit in (50, 1):
        monkeypatch.setattr(start, "DIRECT_ITER", limit)
        out = tmp_path / f"r{limit}.h5"
        done = CliRunner().invoke(main, ["run", str(case), "-o", str(out), "-v"])
        assert done.exit_code == 0, done.output[-2000:]
        lines = [line for line in done.output.splitlines() if "solver.newton: static" in line]
        direct = [line for line in lines if "static (direct)" in line]
        assert len(direct) == (len(lines) if limit == 50 else 1), (limit, len(direct))
        with h5py.File(out) as f:
            sags.append(-float(f["result/x"][30, 2]))
            iterations = int(f["result"].attrs["iterations"])
        assert iterations == len(lines), (iterations, len(lines))
    assert len(lines) > 1  # the continuation's stages after the one direct iteration
    assert abs(sags[1] - sags[0]) < 1e-9, sags
