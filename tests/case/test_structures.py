"""The structure examples (configs/structures/ and configs/formfind/saddle_roof.toml) run
and show what their first lines say: a form-found saddle roof under snow, a guyed mast
under a horizontal load, an elastomer tether net at large strain. In every one the
reactions and the loads sum to zero.

Closed forms used:
- Saddle roof under snow (membrane theory of a shallow hyperbolic paraboloid
  z = (x^2 - y^2) / (2 c)): a load p per plan area is carried by the change of the cable
  forces per width, dn_x / c - dn_y / c = p, so at a node of the h-grid the hanging
  cables gain and the arching ones lose together dT_x - dT_y = p h c.
- Guyed mast with a strut much stiffer than the guys: the top moves by
  u = F / k, k = sum over guys of (EA / L) (e_x . n)^2 + (T / L) (1 - (e_x . n)^2)
  - N_strut / H (the material and geometric stiffness of the guys, the geometric
  softening of the compressed strut).
- Tether net: each tether carries the end force F, so its strain is the law's inverse at
  F: linear F / EA; neo-Hookean lambda - lambda^-2 = 3 F / EA.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from catenet.case import build, load_case
from catenet.formfind.case import write_formfind
from catenet.run import advice
from catenet.run.runner import run_case

CONFIGS = Path(__file__).parents[2] / "configs"
SADDLE = CONFIGS / "formfind" / "saddle_roof.toml"
MAST = CONFIGS / "structures" / "guyed_mast.toml"
TETHER = CONFIGS / "structures" / "tether_net.toml"
HYPAR = CONFIGS / "structures" / "hypar_roof.toml"
SNOW = 800.0  # N/m^2 on plan: 400 N per metre of cable of the 1 m grid (see the case)


def says_what_it_shows(path: Path) -> None:
    lines = path.read_text().splitlines()
    assert len(lines) >= 3 and all(line.startswith("# ") for line in lines[:3])


def balanced(case, result) -> None:
    """Reactions plus loads sum to zero (to the solver's tolerance)."""
    scene = build(case)
    load = scene.loads.external_force(scene.net)
    total = result.reaction.sum(axis=0) + load.sum(axis=0)
    scale = float(np.abs(load).sum() + np.abs(result.reaction).sum())
    assert scale > 0
    assert np.abs(total).max() <= 1e-7 * scale


def test_every_structure_example_is_tested():
    elsewhere = ("mast_load_cases.toml", "hypar_principal.toml")
    tested = {SADDLE, MAST, TETHER, HYPAR, *(CONFIGS / "structures" / f for f in elsewhere)}
    assert set((CONFIGS / "structures").glob("*.toml")) <= tested
    # mast_load_cases.toml: tests/run/test_load_cases.py; hypar_principal.toml:
    # tests/formfind/test_hypar_principal.py
    for path in tested:
        says_what_it_shows(path)


# --------------------------------------------------------------------------- saddle roof


@pytest.fixture(scope="module")
def saddle(tmp_path_factory):
    """The form-found roof, its unloaded rerun and the snow run (as the case says)."""
    tmp = tmp_path_factory.mktemp("saddle")
    written = write_formfind(load_case(SADDLE), tmp / "roof.h5")
    bare_case = load_case(written.case_file)
    bare = run_case(bare_case, tmp / "bare.h5")
    snow_case = load_case(written.case_file, [f"load.line.0.force=[0, 0, {-SNOW / 2}]"])
    snow = run_case(snow_case, tmp / "snow.h5")
    return written, bare, snow_case, snow


def test_saddle_roof_is_the_hypar(saddle):
    written, bare, _, _ = saddle
    found = written.found
    x, y, z = found.x.T
    assert np.abs(z - (x**2 - y**2) / 24.0).max() < 1e-10
    assert bare.converged
    assert np.abs(bare.x - found.x).max() < 1e-8
    np.testing.assert_allclose(bare.tension, found.force, rtol=1e-8)


def test_saddle_roof_under_snow(saddle):
    written, bare, snow_case, snow = saddle
    assert snow.converged
    balanced(snow_case, snow)
    net = written.found.net
    free = ~net.fixed
    dz = snow.x[:, 2] - bare.x[:, 2]
    # Downwards at every free node, by millimetres (against 3 m of rise and sag: the
    # prestressed net is stiff).
    assert dz[free].max() < 0.0
    assert 1e-3 < -dz.min() < 0.05
    centre = int(np.argmin(np.linalg.norm(bare.x[:, :2], axis=1)))
    along = bare.x[net.edges[:, 1]] - bare.x[net.edges[:, 0]]
    hanging = np.abs(along[:, 0]) > np.abs(along[:, 1])  # x-cables: z = x^2 / 24 + ...
    change = snow.tension - bare.tension
    assert change[hanging].min() > 0.0  # every hanging edge gains tension
    assert change[~hanging].max() < 0.0  # every arching edge loses it
    # None slack under moderate snow: the arching cables keep about half their prestress.
    assert snow.tension.min() > 0.3 * bare.tension.min()
    # Membrane theory at the centre node: dT_x - dT_y = p h c (h = 1 m, c = 12 m).
    at = np.any(net.edges == centre, axis=1)
    split = change[at & hanging].mean() - change[at & ~hanging].mean()
    assert split == pytest.approx(SNOW * 1.0 * 12.0, rel=0.03)


# --------------------------------------------------------------------------- hypar roof


def test_hypar_roof_under_snow_on_plan(tmp_path):
    """The roof with its self-weight alone, then with the snow: 800 Pa x 144 m^2 in all,
    carried by the hanging cables gaining what the arching ones lose (membrane theory at
    the middle node: dT_x - dT_y = p h c, h = 2 m, c = 12 m)."""
    snow_case = load_case(HYPAR)
    bare_case = load_case(HYPAR, ["load.area.0.pressure=0"])
    scene = build(snow_case)
    weight = build(bare_case).loads.external_force(scene.net)[:, 2].sum()
    snow_load = scene.loads.external_force(scene.net)[:, 2].sum() - weight
    assert snow_load == pytest.approx(-800.0 * 144.0, rel=1e-12)
    snow = run_case(snow_case, tmp_path / "snow.h5")
    bare = run_case(bare_case, tmp_path / "bare.h5")
    assert snow.converged and bare.converged
    balanced(snow_case, snow)
    net = scene.net
    along = net.nodes[net.edges[:, 1]] - net.nodes[net.edges[:, 0]]
    cable = scene.cables.edge >= 0
    hanging = cable & (np.abs(along[:, 0]) > np.abs(along[:, 1]))
    arching = cable & ~hanging
    change = snow.tension - bare.tension
    assert change[hanging].min() > 0.0 and change[arching].max() < 0.0
    assert snow.tension[cable].min() > 0.3 * 30e3  # none slack
    middle = scene.probe
    assert np.allclose(net.nodes[middle], 0.0)
    at = np.any(net.edges == middle, axis=1)
    split = change[at & hanging].mean() - change[at & arching].mean()
    assert split == pytest.approx(800.0 * 2.0 * 12.0, rel=0.05)


# --------------------------------------------------------------------------- guyed mast


def test_guyed_mast_under_a_horizontal_load(tmp_path):
    case = load_case(MAST)
    r = run_case(case, tmp_path / "mast.h5")
    assert r.converged and r.stable is not False
    balanced(case, r)
    scene = build(case)
    net = scene.net
    top, foot = 1, 0
    e = net.edges
    strut = int(np.flatnonzero(np.all(np.sort(e, axis=1) == [foot, top], axis=1))[0])
    assert not net.law.tension_only[strut] and net.EA[strut] == 1000 * net.EA.min()
    # The strut is in compression and carries the guys' vertical components at the top.
    at_top = np.flatnonzero(np.any(e == top, axis=1) & (np.arange(len(e)) != strut))
    assert len(at_top) == 4
    other = np.where(e[at_top, 0] == top, e[at_top, 1], e[at_top, 0])
    unit = r.x[other] - r.x[top]
    unit /= np.linalg.norm(unit, axis=1)[:, None]
    guys_down = -np.sum(r.tension[at_top] * unit[:, 2])
    assert r.tension[strut] < 0
    assert -r.tension[strut] == pytest.approx(guys_down, rel=1e-6)
    # Per cable: the mast is a strut in compression, not a slack cable.
    assert r.report.cables["mast"].slack_fraction == 0.0
    assert r.report.cables["mast"].max_tension == pytest.approx(r.tension[strut])
    # Windward (anchored at x = -15) gains, leeward (x = +15) loses, the sides hardly change.
    t0 = 20.0e3
    ends = r.x[other]
    windward = at_top[np.argmin(ends[:, 0])]
    leeward = at_top[np.argmax(ends[:, 0])]
    side = at_top[np.abs(ends[:, 0]) < 1.0]
    assert r.tension[windward] > 1.3 * t0 and 0 < r.tension[leeward] < 0.7 * t0
    assert np.allclose(r.tension[side], t0, rtol=1e-3)
    # The top moves with the load, by F / k (closed form in the module docstring).
    u = r.x[top] - net.nodes[top]
    f, ea, length, height = 10.0e3, 2.0e7, 25.0, 20.0
    c2 = (15.0 / 25.0) ** 2
    k = 2 * (ea / length * c2 + t0 / length * (1 - c2)) + 2 * t0 / length - 64.0e3 / height
    assert u[0] == pytest.approx(f / k, rel=0.02)
    assert abs(u[1]) < 1e-9 and abs(u[2]) < 0.01 * u[0]


# --------------------------------------------------------------------------- tether net


@pytest.mark.parametrize("law", ["neo_hookean", "linear"])
def test_tether_net_strains_follow_the_law(law, tmp_path, caplog):
    case = load_case(TETHER, [f"material.law={law}"])
    with caplog.at_level(logging.WARNING):
        r = run_case(case, tmp_path / f"{law}.h5")
    assert r.converged
    balanced(case, r)
    net = build(case).net
    along = np.abs(net.nodes[net.edges[:, 1], 0] - net.nodes[net.edges[:, 0], 0]) > 0
    force, ea = 600.0, 2000.0
    if law == "linear":
        expected = force / ea
    else:
        stretch = brentq(lambda lam: lam - lam**-2 - 3 * force / ea, 1.0, 3.0, xtol=1e-15)
        expected = stretch - 1.0
    from catenet.model import measures

    eps = measures.strain(net, r.x)
    np.testing.assert_allclose(r.tension[along], force, rtol=1e-8)
    np.testing.assert_allclose(eps[along], expected, rtol=1e-8)
    assert np.abs(eps[~along]).max() < 1e-8  # the cords carry nothing
    assert r.max_strain == pytest.approx(expected, rel=1e-8)
    beyond = advice.strain_beyond_law(net, r.x)
    warned = [m for m in caplog.messages if "beyond the material law's range" in m]
    if law == "neo_hookean":
        assert 0.2 < expected < 0.5 and expected == pytest.approx(0.406, abs=1e-3)
        assert beyond is None and not warned
    else:
        assert expected == pytest.approx(0.3) and beyond is not None and warned
