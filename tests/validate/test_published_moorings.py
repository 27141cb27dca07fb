"""Case (v) of ``catenet validate``: the OC3-Hywind mooring lines against the restoring
stiffness published for them (Jonkman 2010, Eq. 5-3), and the data read right: the same
stiffness from the closed-form elastic catenary on a frictionless seabed."""

from __future__ import annotations

import numpy as np
import pytest

from catenet.validate import moorings as m
from catenet.validate.seabed import seabed_catenary


def closed_form_wrench(move: str, d: float) -> np.ndarray:
    """The lines' force and moment about the centreline on the platform, each line the
    elastic catenary on a frictionless seabed."""
    anchors, fairleads = m._lines(move, d)
    force, moment = np.zeros(3), np.zeros(3)
    for a, f in zip(anchors, fairleads, strict=True):
        span = a - f
        X = float(np.hypot(*span[:2]))
        line = seabed_catenary(L=m.LENGTH, EA=m.EA, w=m.WEIGHT, X=X, h=f[2] - a[2])
        pull = line.H * np.array([span[0] / X, span[1] / X, 0.0]) - [0.0, 0.0, line.V]
        force += pull
        moment += np.cross(f, pull)
    return np.concatenate([force, moment])


@pytest.mark.parametrize(
    "move, axis, name",
    [
        ("surge", 0, "K11 surge [N/m]"),
        ("heave", 2, "K33 heave [N/m]"),
        ("yaw", 5, "K66 yaw [N m/rad]"),
    ],
)
def test_the_published_stiffness_is_the_elastic_catenarys(move, axis, name):
    """The table's data give the published numbers through the closed form (to their
    four digits): the lines are the ones the report describes."""
    d = 1e-4
    k = -(closed_form_wrench(move, d)[axis] - closed_form_wrench(move, -d)[axis]) / (2 * d)
    assert k == pytest.approx(m.PUBLISHED[name], rel=6e-4)


def test_catenet_meets_the_published_restoring_stiffness():
    rows = {r["quantity"]: r for r in m.oc3_rows()}
    for name, value in m.PUBLISHED.items():
        r = rows[name]
        assert r["analytic"] == value and r["passed"] is True, r
        assert abs(r["catenet"] / value - 1) <= m.TOLERANCE
    for name in ("fairlead H [N]", "fairlead V [N]"):
        assert rows[name]["error"] < 2e-4 and rows[name]["passed"] is None, rows[name]
