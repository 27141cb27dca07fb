"""Every example case in configs/ runs (as ``catenet run`` runs it) and gives the physics
its comment promises."""

from __future__ import annotations

import math

import h5py
import numpy as np
import pytest
from conftest import CONFIGS, check_xdmf

from catenet.case import load_case
from catenet.run.runner import run_case
from catenet.validate import analytic

FILES = sorted(CONFIGS.glob("*.toml"))
SLOW = ("n34", "damping")  # the largest nets and the time-stepping runs: seconds each
RESULTS: dict[str, dict] = {}


def params():
    for path in FILES:
        marks = [pytest.mark.slow] if any(s in path.stem for s in SLOW) else []
        yield pytest.param(path, id=path.stem, marks=marks)


def test_configs_exist():
    names = {p.stem for p in FILES}
    assert {"catenary", "midpoint_load", "damping_mu0.1", "damping_mu1", "damping_mu10"} <= names
    assert sum(name.startswith("fig4") for name in names) == 9
    for path in FILES:
        assert path.read_text().startswith("# Paper"), f"{path.name}: say what it reproduces"


@pytest.mark.parametrize("path", list(params()))
def test_config_runs(path, tmp_path):
    RESULTS[path.stem] = run_config(path, tmp_path)


def run_config(path, tmp_path) -> dict:
    """Runs one example case as `catenet run` does, checks its file, returns what the
    physics tests need."""
    case = load_case(path)
    out = tmp_path / f"{path.stem}.h5"
    res = run_case(case, out)
    assert res.converged and res.equilibrium, res.message
    with h5py.File(out, "r") as h5:
        a = dict(h5["result"].attrs)
        times = h5["trajectory/time"][()] if "trajectory" in h5 else np.zeros(0)
        series = h5["trajectory/x"][:, int(a["probe"]), 2] if "trajectory" in h5 else None
    assert a["converged"] and a["delta"] > 0
    check_xdmf(out.with_suffix(".xdmf"))
    return {
        "delta": res.report.delta,
        "L": res.report.size,
        "time": res.time,
        "t_end": case.solver.t_end,
        "times": times,
        "series": series,
        "max_strain": res.max_strain,
        "EA": float(np.median(load_scene_EA(case))),
    }


def load_scene_EA(case):
    from catenet.case import build

    return build(case).net.EA


def need(tmp_path, *names):
    """The runs of the named cases: from test_config_runs when it ran in this process,
    else run here (tests may be spread over processes)."""
    for name in names:
        if name not in RESULTS:
            RESULTS[name] = run_config(CONFIGS / f"{name}.toml", tmp_path)
    return [RESULTS[n] for n in names]


def test_catenary_follows_eqs_14_15(tmp_path):
    """Each load step k moves the ends by 0.01 k: the sag follows the inextensible catenary
    at Delta L / L = 0.02 k, to the discretisation error (101 nodes) and the small stretch
    under self-weight (rho g A L / EA ~ 1e-3)."""
    (r,) = need(tmp_path, "catenary")
    sags = -np.asarray(r["series"])
    expected = [analytic.catenary_sag(1.0, 0.02 * k) for k in range(1, 11)]
    np.testing.assert_allclose(r["times"], np.arange(1, 11) / 10)
    np.testing.assert_allclose(sags, expected, rtol=5e-3)


def test_midpoint_load_follows_eq_17(tmp_path):
    (r,) = need(tmp_path, "midpoint_load")
    F = 94.25 * np.arange(1, 11) / 10
    expected = [analytic.midpoint_load_deflection(f, 1.0, r["EA"]) for f in F]
    np.testing.assert_allclose(-np.asarray(r["series"]), expected, rtol=1e-6)
    assert r["max_strain"] < 0.05  # the paper's limit of linear elasticity


def test_nets_stiffen_with_n_and_soften_with_alpha(tmp_path):
    """Fig. 4 and 7: more cables deflect less; turning them from 0 to pi/4 deflects more."""
    names = {
        (n, a): f"fig4{letter}_n{n}_alpha_{a}"
        for letter, (n, a) in zip(
            "abcdefghi",
            [(n, a) for n in (10, 22, 34) for a in ("0", "pi6", "pi4")],
            strict=True,
        )
    }
    runs = need(tmp_path, *names.values())
    deltas = {key: r["delta"] for key, r in zip(names, runs, strict=True)}
    for a in ("0", "pi6", "pi4"):
        assert deltas[10, a] > deltas[22, a] > deltas[34, a]
    for n in (10, 22, 34):
        assert deltas[n, "0"] < deltas[n, "pi6"] < deltas[n, "pi4"]
    assert all(0.02 < d < 0.1 for d in deltas.values())


def test_damping_changes_the_way_not_the_equilibrium(tmp_path):
    """App. A: the same equilibrium for mu = 0.1, 1, 10, equal to the static one of
    Fig. 4a, reached long before t_end (dynamic relaxation stops at rest)."""
    runs = need(tmp_path, "damping_mu0.1", "damping_mu1", "damping_mu10", "fig4a_n10_alpha_0")
    static = runs[-1]["delta"]
    for r in runs[:-1]:
        assert r["delta"] == pytest.approx(static, rel=1e-6)
        assert r["time"] < 0.5 * r["t_end"]
        assert r["times"][0] == 0.0 and math.isclose(r["times"][-1], r["time"])
    # Lighter damping overshoots further on the way.
    overshoot = [float(np.max(-np.asarray(r["series"]))) - static for r in runs[:-1]]
    assert overshoot[0] >= overshoot[1] >= overshoot[2] - 1e-9
