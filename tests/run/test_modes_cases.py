"""Which analyses take load cases: `catenet run` (static) solves each from the base
state; `catenet modes` finds the modes about the base state, or with --case NAME about
the state under one load case or combination; a dynamic run refuses them (exit 2).

The modes under a load case are those of the net in equilibrium under the base loads
plus the case's: a plain case with those loads in [load] has the same frequencies (the
same state, reached by the same load steps from the same geometry)."""

from __future__ import annotations

import tomllib

import h5py
import numpy as np
from click.testing import CliRunner

from catenet.case import dumps_toml, parse_case
from catenet.cli import main
from catenet.run.modes import modes_case
from tests.conftest import CONFIGS

MAST = CONFIGS / "structures" / "mast_load_cases.toml"


def mast(**changes) -> dict:
    """The bundled mast of load cases, with mass (steel guys of 10 mm radius)."""
    data = tomllib.loads(MAST.read_text())
    data["material"] |= {"density": 7850.0, "radius": 0.01}
    return data | changes


def test_modes_under_a_load_case_are_those_of_the_net_under_its_loads(tmp_path):
    """ULS_wind_x = 1.5 x 10 kN at the top: the modes about it are those of the mast
    with 15 kN at its top; the leeward guy loses tension, so the lowest frequency drops
    below the base state's."""
    under = modes_case(parse_case(mast()), tmp_path / "c.h5", count=4, load_case="ULS_wind_x")
    plain = mast(load={"point": [{"node": "top", "force": [15.0e3, 0.0, 0.0]}]})
    for key in ("load_case", "combination"):
        del plain[key]
    want = modes_case(parse_case(plain), tmp_path / "p.h5", count=4)
    assert under.load_case == "ULS_wind_x"
    np.testing.assert_allclose(under.result.x, want.result.x, rtol=0, atol=1e-12)
    np.testing.assert_allclose(under.modes.frequency, want.modes.frequency, rtol=1e-10)
    base = modes_case(parse_case(mast()), tmp_path / "b.h5", count=4)
    assert base.load_case is None and under.modes.frequency[0] < base.modes.frequency[0]
    with h5py.File(tmp_path / "c.h5") as h5:
        assert h5["modes"].attrs["load_case"] == "ULS_wind_x"
        assert list(h5["cases"]) == ["ULS_wind_x"]
        np.testing.assert_array_equal(h5["modes/frequency"][:], under.modes.frequency)
    with h5py.File(tmp_path / "b.h5") as h5:
        assert "load_case" not in h5["modes"].attrs


def test_modes_of_the_base_state_ignore_no_load_and_say_so(tmp_path):
    """Without --case the modes are the base state's: the same as the case without its
    load cases; the summary says which state and how to ask for another."""
    data = mast()
    bare = {k: v for k, v in data.items() if k not in ("load_case", "combination")}
    with_cases = modes_case(parse_case(data), tmp_path / "a.h5", count=3)
    without = modes_case(parse_case(bare), tmp_path / "b.h5", count=3)
    np.testing.assert_array_equal(with_cases.modes.frequency, without.modes.frequency)
    path = tmp_path / "mast.toml"
    path.write_text(dumps_toml(data))
    r = CliRunner().invoke(main, ["modes", str(path), "-k", "2", "-o", str(tmp_path / "c.h5")])
    assert r.exit_code == 0, r.output
    assert "equilibrium  the base state (--case NAME: under a load case): " in r.output
    r = CliRunner().invoke(
        main, ["modes", str(path), "-k", "2", "--case", "ice", "-o", str(tmp_path / "d.h5")]
    )
    assert r.exit_code == 0, r.output
    assert "equilibrium  under ice, from the base state: " in r.output
    r = CliRunner().invoke(main, ["modes", str(path), "--case", "snow"])
    assert r.exit_code == 2
    assert "--case 'snow': no [[load_case]] or [[combination]] is named so" in r.output


def test_a_dynamic_run_refuses_load_cases(tmp_path):
    data = mast(solver={"method": "dynamic", "t_end": 0.1, "dt": 0.01})
    path = tmp_path / "mast.toml"
    path.write_text(dumps_toml(data))
    r = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "d.h5")])
    assert r.exit_code == 2
    assert (
        "solver.method = 'dynamic': [[load_case]] and [[combination]] are static analyses "
        "from the base state: set solver.method = 'static'" in r.output
    )
    assert not (tmp_path / "d.h5").exists()
