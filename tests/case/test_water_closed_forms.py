"""Closed forms of a line in water, from case files (docs/howto/mooring-dynamics.md): its
buoyancy is the displaced water's weight, and a line in a uniform current is statically
the same line under the current's drag as a given distributed load."""

from __future__ import annotations

import numpy as np
import pytest

from catenet.case import parse_case
from catenet.case.scene import build
from catenet.model.net import Loads
from catenet.scene import Scene
from catenet.solver.path import Settings, solve
from catenet.terms.water import WaterForce

RHO_W, G = 1025.0, 9.81


def hanging(**water) -> dict:
    """A 30 m steel wire rope (A = 2e-3 m^2) hanging between two supports 20 m apart,
    8 m below the surface."""
    return {
        "geometry": {
            "kind": "cable",
            "start": [0.0, 0.0, -8.0],
            "end": [20.0, 0.0, -8.0],
            "nodes": 31,
            "length": 30.0,
        },
        "material": {"EA": 2e8, "area": 2e-3, "density": 7850.0, "hydro_diameter": 0.06},
        "water": {"density": RHO_W, **water},
        "load": {"gravity": [0.0, 0.0, -G]},
        "solver": {"method": "static"},
    }


def test_buoyancy_is_the_displaced_waters_weight():
    """The supports of a submerged line carry its weight less the displaced water's,
    (rho - rho_w) A L0 g, to the solver's tolerance; above the water, its whole weight."""
    c = parse_case(hanging())
    r = solve(build(c), Settings.of(c.solver))
    up = r.reaction[:, 2].sum()
    assert up == pytest.approx((7850.0 - RHO_W) * 2e-3 * 30.0 * G, rel=1e-9)
    dry = parse_case(hanging(surface=-100.0))  # the still water far below
    r = solve(build(dry), Settings.of(dry.solver))
    assert r.reaction[:, 2].sum() == pytest.approx(7850.0 * 2e-3 * 30.0 * G, rel=1e-9)


def test_a_line_in_a_current_is_the_line_under_its_drag_as_a_load():
    """A line in a uniform current (crossflow and along it) comes to rest where the
    same line in still water does under the current's drag on it at that rest state
    given as nodal loads (1/2 rho_w d (cd_n |u_n| u_n + pi cd_t |u_t| u_t) l / 2 from each
    half edge): the drag term is that load, to the solver's tolerance."""
    current = [[-50.0, 0.4, 0.9], [0.0, 0.4, 0.9]]
    case = hanging(current=current)
    case["material"].update(cd_n=1.2, cd_t=0.5)
    c = parse_case(case)
    scene = build(c)
    r = solve(scene, Settings.of(c.solver))
    drag = next(t for t in scene.terms if isinstance(t, WaterForce))
    drag.begin_step(r.x, None)  # the current's drag on the line at rest at its solution
    load = drag.still.copy()
    assert np.abs(load).max() > 10.0 and np.abs(r.x[:, 1]).max() > 0.5  # it acts
    still = parse_case(hanging())  # the same line, still water: buoyancy and weight
    plain = build(still)
    force = plain.loads.external_force(plain.net) + load
    loaded = Scene.of(plain.net, Loads(force=force)).with_terms(*plain.terms)
    r2 = solve(loaded, Settings.of(still.solver))
    assert np.abs(r2.x - r.x).max() < 1e-7 * 30.0
    assert np.allclose(r2.tension, r.tension, rtol=1e-7)
