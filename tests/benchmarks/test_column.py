"""The buckled cantilever column of benchmarks/peers/dismech_column.py, catenet's side:
its tip against the elastica of the buckled column (Timoshenko and Gere), above the
critical load where the answer is most sensitive to the bending stiffness."""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks.peers import dismech_column as dc


def test_the_elastica_of_the_column_starts_at_eulers_load():
    axial, lateral = dc.elastica_column(1.0 + 1e-10)
    assert axial == pytest.approx(1.0, abs=1e-8) and lateral < 1e-4
    # Timoshenko and Gere's table of the buckled column: a tip turned 60 deg at
    # P / P_cr = 1.152 stands at x = 0.741 L, y = 0.593 L
    axial, lateral = dc.elastica_column(1.152)
    assert axial == pytest.approx(0.741, abs=2e-3) and lateral == pytest.approx(0.593, abs=1e-3)
    assert dc.P_CR == pytest.approx(math.pi**2 / 4.0)


@pytest.mark.parametrize("ratio", [1.1, 1.5])
def test_catenets_buckled_column_has_the_elastica_tip_at_50_edges(ratio):
    """P = 1.1 and 1.5 P_cr with a lateral nudge of 1e-4 P: the tip within 1e-3 L of the
    elastica (5.5e-4 and 6.5e-4 here; 1 % of bending stiffness would move it 5 % at
    1.1 P_cr)."""
    tip, _ = dc.column_tip(ratio, 50)
    exact = np.array(dc.elastica_column(ratio))
    assert np.abs(tip - exact).max() < 1e-3, (tip, exact)
