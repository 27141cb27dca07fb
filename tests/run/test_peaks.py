"""Peaks over a run (contract §7: /result/peak_tension, /result/peak_tension_time):
each edge's largest tension over every time step or load step, not only the frames a
file keeps, and each node's largest displacement."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import h5py
import numpy as np
import pytest

from catenet.case import parse_case
from catenet.run.runner import run_case
from catenet.validate.seabed import seabed_catenary


def dropped_cable(every: int, t_end: float = 0.6) -> dict:
    """A 10 m cable, 1 % slack, dropped from its chord under gravity with light damping:
    it overshoots its catenary, so its tension peaks early and then settles lower."""
    return {
        "geometry": {
            "kind": "cable",
            "start": [0.0, 0.0, 0.0],
            "end": [10.0, 0.0, 0.0],
            "length": 10.1,
            "nodes": 11,
        },
        "material": {"EA": 5.0e4, "density": 7800.0, "radius": 0.005},
        "load": {"gravity": [0.0, 0.0, -9.81]},
        "solver": {"method": "dynamic", "dt": 0.01, "damping": 0.2, "t_end": t_end},
        "output": {"every": every},
    }


def read(path):
    with h5py.File(path) as h5:
        r = h5["result"]
        return (
            {k: r[k][:] for k in ("peak_tension", "peak_tension_time", "tension", "x")},
            dict(r.attrs),
            h5["trajectory/tension"][:],
            h5["trajectory/time"][:],
            h5["trajectory/x"][:],
            h5["mesh/nodes"][:],
        )


def test_dynamic_peaks_cover_every_step_not_only_the_stored_frames(tmp_path):
    """With every = 1 the peak is the maximum over the stored frames (frame 0, the start,
    included), at the frame's time, bit for bit; with every = 4 the same run gives the
    same peaks although its frames miss them, and they are >= every stored frame's."""
    every1 = run_case(parse_case(dropped_cable(1)), tmp_path / "a.h5")
    every4 = run_case(parse_case(dropped_cable(4)), tmp_path / "b.h5")
    assert every1.steps == every4.steps > 20
    r1, a1, tension1, time1, x1, nodes = read(tmp_path / "a.h5")
    r4, a4, tension4, _, _, _ = read(tmp_path / "b.h5")
    assert len(tension1) == every1.steps + 1
    assert np.array_equal(r1["peak_tension"], tension1.max(axis=0))
    assert np.array_equal(r1["peak_tension_time"], time1[np.argmax(tension1, axis=0)])
    assert np.array_equal(r4["peak_tension"], r1["peak_tension"])
    assert np.array_equal(r4["peak_tension_time"], r1["peak_tension_time"])
    assert np.all(r4["peak_tension"] >= tension4.max(axis=0))
    # The peak is a design value the final state does not show (the cable overshoots).
    assert r1["peak_tension"].max() > 1.2 * r1["tension"].max()
    assert tension4.max() < r4["peak_tension"].max()  # and every = 4 frames miss it
    # The attributes name the largest one, its edge and time.
    e = int(np.argmax(r1["peak_tension"]))
    assert a4["peak_tension"] == r1["peak_tension"][e] and a4["peak_tension_edge"] == e
    assert a4["peak_tension_time"] == r1["peak_tension_time"][e]
    assert a4["max_tension"] == r1["tension"].max() < a4["peak_tension"]
    # Each node's peak displacement over the run.
    with h5py.File(tmp_path / "b.h5") as h5:
        peak_u = h5["result/peak_displacement"][:]
        when = h5["result/peak_displacement_time"][:]
    u = np.linalg.norm(x1 - nodes, axis=2)
    assert np.array_equal(peak_u, u.max(axis=0))
    free = np.arange(1, 10)
    assert np.array_equal(when[free], time1[np.argmax(u[:, free], axis=0)])
    assert a4["peak_displacement"] == pytest.approx(u[:, free].max(), rel=0, abs=0)
    assert every4.report.summary["peak_tension"] == a4["peak_tension"]


def test_static_peaks_are_over_the_load_steps(tmp_path):
    """A static run in load steps: the peak is each edge's largest tension over the load
    steps (its time the load factor); under a load that only grows, the last step's."""
    data = dropped_cable(1)
    data["solver"] = {"method": "static", "steps": 4}
    data["load"] = {"point": [{"node": "midpoint", "force": [0.0, 0.0, -200.0]}]}
    result = run_case(parse_case(data), tmp_path / "s.h5")
    r, a, tension, time, _, _ = read(tmp_path / "s.h5")
    assert np.array_equal(time, [0.25, 0.5, 0.75, 1.0])
    assert np.array_equal(r["peak_tension"], tension.max(axis=0))
    assert np.array_equal(r["peak_tension"], r["tension"])
    assert np.all(r["peak_tension_time"] == 1.0)
    assert a["peak_tension"] == a["max_tension"] == result.report.summary["peak_tension"]


def test_a_restart_goes_on_from_the_earlier_peaks(tmp_path):
    """A run to 0.5 s (past the cable's snap at 0.45 s) restarted to 0.6 s ends with the
    peaks of the uninterrupted run to 0.6 s: the snap is before the restart."""
    run_case(parse_case(dropped_cable(1)), tmp_path / "whole.h5")
    run_case(parse_case(dropped_cable(1, t_end=0.5)), tmp_path / "first.h5")
    second = run_case(
        parse_case(dropped_cable(1)), tmp_path / "second.h5", restart=tmp_path / "first.h5"
    )
    a, _, _, _, _, _ = read(tmp_path / "whole.h5")
    b, _, tension_b, time_b, _, _ = read(tmp_path / "second.h5")
    assert time_b[0] == pytest.approx(0.5) and np.all(a["peak_tension_time"] < 0.5)
    assert tension_b.max() < 0.8 * a["peak_tension"].max()  # after 0.5 s: no such peak
    assert np.allclose(b["peak_tension"], a["peak_tension"], rtol=1e-9, atol=0)
    assert np.allclose(b["peak_tension_time"], a["peak_tension_time"], rtol=0, atol=1e-12)
    assert second.report.summary["peak_tension"] == pytest.approx(a["peak_tension"].max(), rel=1e-9)


def test_a_restart_from_a_run_to_rest_counts_peaks_from_its_own_start(tmp_path):
    """The documented way to start from equilibrium: the dropped cable relaxed to rest
    (t_end = "rest": its overshoot is a pseudo-time transient), then restarted as a
    physical run. The relaxation's peaks are not carried: the restarted run's peaks are
    its own (no peak before its start, none above its own frames)."""
    relax = dropped_cable(1)
    relax["solver"]["t_end"] = "rest"
    relax["solver"]["damping"] = 1.0
    run_case(parse_case(relax), tmp_path / "rest.h5")
    with h5py.File(tmp_path / "rest.h5") as h5:
        t_rest = float(h5["result"].attrs["time"])
        relax_peak = float(h5["result/peak_tension"][()].max())
    go_on = dropped_cable(1, t_end=t_rest + 0.2)
    run_case(parse_case(go_on), tmp_path / "on.h5", restart=tmp_path / "rest.h5")
    b, _, tension_b, time_b, _, _ = read(tmp_path / "on.h5")
    assert time_b[0] == pytest.approx(t_rest)
    assert np.all(b["peak_tension_time"] >= t_rest)
    assert np.allclose(b["peak_tension"], tension_b.max(axis=0), rtol=1e-12, atol=0)
    assert relax_peak > b["peak_tension"].max()  # the relaxation's stays behind


def mooring_line() -> dict:
    """The line of docs/howto/mooring-line.md (30 m, 10 N/m, EA = 1e6 N, from an anchor on
    the bed to a fairlead 27 m away and 8 m up), as a user copies it from there."""
    text = (Path(__file__).resolve().parents[2] / "docs/howto/mooring-line.md").read_text()
    block = re.search(r"file: mooring.toml -->\n```toml\n(.*?)```", text, re.S)
    assert block, "docs/howto/mooring-line.md lost its mooring.toml"
    return tomllib.loads(block.group(1))


def test_a_mooring_line_relaxed_to_rest_and_surged_reports_its_real_peak(tmp_path):
    """The verdict issue's case: a mooring line relaxed to rest (its pseudo-time peak is
    15.9 kN, 87 times the line's real tension) and restarted under a slow 1 m surge of its
    fairlead (4 s, damped). The restarted run's peak is its own and the closed form's:
    the elastic catenary on the seabed gives 182.5 N at rest and 337.7 N at the surged
    fairlead; the peak lies between them, a few per cent above the latter (the line's
    inertia), and the line never goes slack."""
    rest = mooring_line()
    rest["solver"] = {"method": "dynamic", "t_end": "rest"}
    run_case(parse_case(rest), tmp_path / "rest.h5")
    with h5py.File(tmp_path / "rest.h5") as h5:
        t_rest = float(h5["result"].attrs["time"])
        relax_peak = float(h5["result/peak_tension"][()].max())

    surge = mooring_line()
    surge["geometry"]["sets"] = {"fairlead": [1]}
    surge["supports"] = {
        "move": [
            {
                "node": "fairlead",
                "displacement": [1.0, 0.0, 0.0],
                "history": [[t_rest, 0.0], [t_rest + 4.0, 1.0]],
            }
        ]
    }
    surge["solver"] = {"method": "dynamic", "dt": 0.05, "damping": 0.5, "t_end": t_rest + 6.0}
    surge["output"] = {"every": 1}
    outcome = run_case(parse_case(surge), tmp_path / "surge.h5", restart=tmp_path / "rest.h5")
    b, _, tension, time, _, _ = read(tmp_path / "surge.h5")

    w = 1019.4e-3 * 9.81
    at_rest = seabed_catenary(L=30.0, EA=1e6, w=w, X=27.0, h=7.995)
    surged = seabed_catenary(L=30.0, EA=1e6, w=w, X=28.0, h=7.995)
    quasi_static = float(np.hypot(surged.H, surged.V))
    peak = outcome.report.summary["peak_tension"]
    assert peak == pytest.approx(b["peak_tension"].max(), rel=1e-12)
    assert np.hypot(at_rest.H, at_rest.V) < quasi_static <= peak < 1.05 * quasi_static
    assert relax_peak > 40 * peak  # the relaxation's pseudo-time peak stays behind
    assert np.all(b["peak_tension_time"] >= t_rest) and time[0] == pytest.approx(t_rest)
    assert np.allclose(b["peak_tension"], tension.max(axis=0), rtol=1e-12, atol=0)
    assert tension.min() > 0.5 * at_rest.H  # never slack
