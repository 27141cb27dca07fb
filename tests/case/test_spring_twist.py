"""A twisting rod's end on a 6x6 spring that holds its twist (``[[supports.spring]]``,
``catenet.model.rodends.twist_ends``): the spring's twist stiffness k_t about the rod's
axis in series with the rod's own, L / GJ + 1 / k_t, in statics (a shaft turned at its
clamp) and in the modes (a shaft clamped at one end, on a torsional spring at the
other: tan(beta) = -GJ beta / (k_t L)); a 6x6 that couples the twist with its other rows
is refused at a twisting rod's end."""

from __future__ import annotations

import math

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.case import dumps_toml
from catenet.cli import main

L, GJ, EI, PHI = 2.0, 100.0, 200.0, 0.1
K_T = GJ / L  # N m/rad: k_t L / GJ = 1
RHO_J = 0.02  # kg m, the mass polar moment per length


def _shaft(nodes: int, stiffness, turned: bool = True) -> dict:
    data = {
        "geometry": {"kind": "cable", "start": [0.0, 0.0, 0.0], "end": [L, 0.0, 0.0],
                     "nodes": nodes},
        "material": {"EA": 1e7, "EI": EI, "GJ": GJ, "tension_only": False,
                     "area": 1e-4, "density": 7850.0, "polar_inertia": RHO_J},
        "supports": {"fixed": ["start"], "clamped": ["start"],
                     "spring": [{"nodes": ["end"], "stiffness": stiffness}]},
    }  # fmt: skip
    if turned:
        data["supports"]["twist"] = [{"nodes": ["start"], "angle": PHI}]
    return data


def _invoke(tmp_path, data, command="run", *args):
    case = tmp_path / "shaft.toml"
    case.write_text(dumps_toml(data))
    out = tmp_path / "out.h5"
    done = CliRunner().invoke(main, [command, str(case), "-o", str(out), *args])
    return done, out


def test_a_spring_holds_the_twist_in_series_with_the_rod(tmp_path):
    """The shaft turned by phi at its clamp, its other end on [k, k, k, k_t, k, k] (the
    rod along x): the twisting moment phi / (L / GJ + 1 / k_t), exactly; the spring's
    end turns by M / k_t. Without the spring's twist stiffness the rod untwists."""
    done, out = _invoke(tmp_path, _shaft(21, [1e6, 1e6, 1e6, K_T, 1e4, 1e4]))
    assert done.exit_code == 0, done.output
    with h5py.File(out) as f:
        torque = f["result/twisting_moment"][()]
    assert np.allclose(torque, PHI / (L / GJ + 1.0 / K_T), rtol=1e-9)
    done, out = _invoke(tmp_path, _shaft(21, [1e6, 1e6, 1e6, 0.0, 1e4, 1e4], turned=False))
    assert done.exit_code == 0, done.output


def test_the_modes_see_the_springs_twist(tmp_path):
    """The shaft clamped at one end, on the torsional spring k_t = GJ / L at the other:
    its first torsional frequency beta / (2 pi L) sqrt(GJ / rho J_p), tan(beta) = -beta
    (beta = 2.0288), to 1e-3 at 40 edges; a stiffer spring raises it towards the
    clamped-clamped shaft's pi."""
    from scipy.optimize import brentq

    beta = brentq(lambda b: math.tan(b) + b, 1.6, 3.0)
    expected = beta / (2 * math.pi * L) * math.sqrt(GJ / RHO_J)
    found = []
    for k_t in (K_T, 1e3 * K_T):
        data = _shaft(41, [1e6, 1e6, 1e6, k_t, 1e4, 1e4], turned=False)
        done, out = _invoke(tmp_path, data, "modes", "--count", "12")
        assert done.exit_code == 0, done.output
        with h5py.File(out) as f:
            share, frequency = f["modes/twist_share"][()], f["modes/frequency"][()]
        found.append(float(frequency[share > 0.5][0]))  # the lowest torsional mode
    assert found[0] == pytest.approx(expected, rel=1e-3)
    clamped = 1.0 / (2 * L) * math.sqrt(GJ / RHO_J)  # pi / (2 pi L) sqrt(GJ / rho J)
    assert found[0] < found[1] < clamped * (1 + 1e-3) and found[1] > 0.99 * clamped


def test_a_6x6_coupling_the_twist_with_other_rows_is_refused(tmp_path):
    k6 = np.diag([1e6, 1e6, 1e6, K_T, 1e4, 1e4])
    k6[3, 4] = k6[4, 3] = 10.0  # the twist about x coupled with the turn about y
    done, out = _invoke(tmp_path, _shaft(21, k6.tolist()))
    assert done.exit_code == 2, done.output
    said = " ".join(done.output.split())
    assert "supports.spring[0].stiffness: node 20 is the end of a rod that twists" in said
    assert "couples the twist about the rod's axis" in said and "Traceback" not in said
