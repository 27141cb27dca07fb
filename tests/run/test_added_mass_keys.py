"""The case keys of the added mass of water (material.added_mass = Ca,
material.water_density = rho_w): each edge adds Ca rho_w A l0 sideways in ``catenet
modes``; bad values exit 2 with the key path."""

from __future__ import annotations

import numpy as np
import pytest

import catenet
from catenet.case import build, parse_case
from catenet.errors import ConfigError
from catenet.run.modes import added_line, modes_case

RHO, AREA, EA, T = 7850.0, 1e-4, 2e7, 5000.0  # steel wire, N
RHO_W, CA = 1025.0, 1.0


def mooring(**material) -> dict:
    return {
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [10, 0, 0], "nodes": 41},
        "material": {"EA": EA, "area": AREA, "density": RHO, "prestress": T, **material},
    }


def test_case_keys_give_the_added_mass(tmp_path):
    """material.added_mass = Ca, material.water_density = rho_w: each edge Ca rho_w A l0;
    ``catenet modes`` (modes_case) scales the lateral frequencies as the API does."""
    case = parse_case(mooring(added_mass=CA, water_density=RHO_W))
    scene = build(case)
    line = added_line(case, scene)
    assert np.allclose(line, CA * RHO_W * AREA * scene.net.rest_length, rtol=1e-14)
    assert added_line(parse_case(mooring()), build(parse_case(mooring()))) is None
    wet = modes_case(case, tmp_path / "wet.h5", count=4).modes
    dry = modes_case(parse_case(mooring()), tmp_path / "dry.h5", count=4).modes
    assert np.allclose(wet.omega2, dry.omega2 * RHO / (RHO + CA * RHO_W), rtol=1e-9)
    api = catenet.modes(scene, k=4, added=line)
    assert np.allclose(api.omega2, wet.omega2, rtol=1e-12)


def test_bad_added_mass():
    with pytest.raises(ConfigError, match=r"material.added_mass = -1.*must be finite and >= 0"):
        parse_case(mooring(added_mass=-1))
    with pytest.raises(ConfigError, match=r"material.water_density = 0.*> 0"):
        parse_case(mooring(water_density=0))
    case = mooring(added_mass=1.0)
    del case["material"]["area"]
    case["material"]["density"] = 0.0
    parsed = parse_case(case)
    with pytest.raises(ConfigError, match=r"material.added_mass = 1.0: .*cross-section"):
        added_line(parsed, build(parsed))
