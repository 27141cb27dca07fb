"""configs/contact/envisat_capture.toml, short: a tether net thrown at a free tumbling
8 t box in orbit. The box is a free body (four nodes, its mass and inertia), the run's
summary names its spin, the time of first contact and the tether's peak load, no node is
ever inside the box, and the box takes the net's momentum (net + box keep it where the
tether is slack)."""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pytest

from catenet.case import build, load_case
from catenet.terms.rigid_contact import BodyContact

CAPTURE = Path(__file__).parents[2] / "configs" / "contact" / "envisat_capture.toml"


def test_the_capture_scene_runs_short_and_reports_the_contact(tmp_path):
    from click.testing import CliRunner

    from catenet.cli import main

    out = tmp_path / "capture.h5"
    args = ["run", str(CAPTURE), "-o", str(out), "--set", "solver.t_end=1.45"]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    line = next(s for s in res.output.splitlines() if s.startswith("body"))
    assert "obstacle[0] (box): spin 3.49" in line and "first contact at t = 1.3" in line
    # the tether's peak load over every step, which the final state (slack) hides
    tether = next(s for s in res.output.splitlines() if s.startswith("cable        tether:"))
    with h5py.File(out) as f:
        edges = np.flatnonzero(f["mesh/cable"][()] == 0)
        peak = f["result/cable_peak_tension"][0]
        when = f["result/cable_peak_tension_time"][0]
        assert f["mesh"].attrs["cable_names"][0] == "tether" and len(edges) == 8
        assert peak == f["result/peak_tension"][edges].max() > 1.0
        assert np.all(peak >= f["trajectory/tension"][:, edges])
    assert f"max tension 0 N, peak {peak:.6g} N at t = {when:.4g} s" in tether
    scene = build(load_case(CAPTURE, ["solver.t_end=1.45"]))
    (body,) = scene.rigid
    assert body.mass == 8000.0
    assert body.inertia == pytest.approx(8000.0 / 3 * np.diag([8.0, 29.0, 29.0]))
    contact = next(t for t in scene.terms if isinstance(t, BodyContact))
    with h5py.File(out) as f:
        x = np.asarray(f["trajectory/x"])
        v = np.asarray(f["trajectory/v"])
        spin = np.asarray(f["trajectory/obstacles/0/angular_velocity"])
    gaps = np.array([contact.gap(xk).min() for xk in x])
    assert gaps.min() > 0.0 and gaps[-1] < contact.dhat  # touching, never inside
    assert np.linalg.norm(spin[0]) == pytest.approx(np.hypot(0.035, 0.05))
    # The tether is still slack: net and box keep their momentum between them.
    m = scene.net.mass[:, None]
    free = ~scene.net.fixed
    p = np.array([(m * vk)[free].sum(axis=0) for vk in v])
    assert np.abs(p - p[0]).max() < 1e-6 * np.abs(p[0]).max()
