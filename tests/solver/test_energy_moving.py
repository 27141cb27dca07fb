"""The energy verdict of runs with an obstacle on a prescribed motion: the obstacle's work
is booked (``external_work``), and the balance is judged as in any other run. A plate
pushing a rope balances within a small share of its work; newmark, which gains energy
in the plate's impact, is stopped by the verdict (before, such runs were not judged and
it ended as an answer with 640 J from nothing)."""

from __future__ import annotations

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

import catenet as cn
from catenet.case import build, dumps_toml, parse_case
from catenet.cli import main
from catenet.solver.energy import EnergyError

#: A rope of 4 m (prestress 100 N) and a plate pushed into its middle sideways, its speed
#: ramped from 0 to 1 m/s over 0.3 s.
ROPE = {
    "title": "a plate pushes a rope",
    "geometry": {"kind": "cable", "start": [0.0, 0.0, 0.0], "end": [4.0, 0.0, 0.0], "nodes": 41},
    "material": {"E": 2e9, "radius": 0.004, "density": 1100.0, "prestress": 100.0},
    "obstacle": [
        {
            "kind": "box",
            "center": [2.0, -0.15, 0.0],
            "half_size": [0.3, 0.05, 0.2],
            "velocity": [0.0, 1.0, 0.0],
            "history": [[0.0, 0.0], [0.3, 1.0]],
            "distance": 0.01,
        }
    ],
    "solver": {"method": "dynamic", "dt": 0.005, "t_end": 0.6},
}


@pytest.mark.parametrize("integrator", ["bdf2", "implicit_euler"])
def test_a_plate_pushing_a_rope_balances(tmp_path, integrator):
    """The plate's work (77 J: it stretches the rope 0.36 m sideways) is what the rope
    holds, to 1e-3 of it at every step; the run is judged and passes."""
    case = tmp_path / "rope.toml"
    case.write_text(dumps_toml({**ROPE, "solver": {**ROPE["solver"], "integrator": integrator}}))
    out = tmp_path / "rope.h5"
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(out)])
    assert done.exit_code == 0, done.output
    with h5py.File(out) as f:
        energy = f["trajectory/energy"][:]
        columns = list(f["trajectory/energy"].attrs["columns"])
    work = energy[:, columns.index("external_work")]
    held = energy[:, :3].sum(axis=1)
    assert work[-1] > 50.0 and abs(held[-1] - held[0] - work[-1]) < 2e-3 * work[-1]
    assert np.abs(energy[:, columns.index("numerical")]).max() < 2e-3 * work[-1]


@pytest.mark.parametrize("speed", [1.0, 3.0])
def test_newmark_gaining_energy_at_a_moving_plate_is_stopped(speed):
    """Newmark (rho_inf 0.95, undamped), which a case file refuses with contact, through
    Python's solve: the plate hits the rope at constant speed and the integrator creates
    energy; the verdict stops the run."""
    data = {**ROPE, "solver": {**ROPE["solver"], "damping": 0.0}}
    plate = {k: v for k, v in ROPE["obstacle"][0].items() if k != "history"}
    data["obstacle"] = [{**plate, "velocity": [0.0, speed, 0.0]}]
    parsed = parse_case(data)
    settings = cn.Settings.of(parsed.solver, integrator="newmark", rho_inf=0.95)
    with pytest.raises(EnergyError, match="the integrator creates energy"):
        cn.solve(build(parsed), settings)


def test_a_net_at_rest_beside_a_moving_plate_is_no_false_alarm(tmp_path):
    """A prestress-free cable at rest, no gravity, a plate brought down to 5.5 mm above
    it (its free node carried into each step's start, the edge never touched): every
    energy is round-off (1e-49 J of kinetic energy appeared where the largest energy was
    of that size, and the verdict called it created); below the energy of a state known
    to 16 eps of its size the remainder is not judged."""
    data = {
        "geometry": {"kind": "cable", "start": [0.0, 0.0, 0.0], "end": [4.0, 0.0, 0.0], "nodes": 3},
        "material": {"E": 1e9, "radius": 0.005, "density": 1000.0},
        "supports": {"fixed": ["start", "end"]},
        "obstacle": [
            {
                "kind": "box", "center": [0.3, 0.0, 0.3075], "half_size": [0.2, 0.5, 0.002],
                "velocity": [0.0, 0.0, -1.0], "history": [[0.0, 1.0], [0.29, 1.0], [0.3, 0.0]],
            }
        ],
        "solver": {"method": "dynamic", "dt": 0.02, "t_end": 1.0, "edge_contact": True},
    }  # fmt: skip
    case = tmp_path / "by.toml"
    case.write_text(dumps_toml(data))
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(tmp_path / "by.h5")])
    assert done.exit_code == 0, done.output
