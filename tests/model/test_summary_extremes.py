"""The summary's extremes (``catenet.model.summary.first_extreme``): the first member
within round-off of the extreme is named, also where the extreme is infinite."""

from __future__ import annotations

import math

import numpy as np

from catenet.model.summary import first_extreme


def test_members_equal_to_round_off_name_the_first():
    values = np.array([1.0, 3.0, 3.0 * (1 + 1e-15), 2.0])
    assert first_extreme(values, np.arange(4)) == 1
    assert first_extreme(values, np.arange(4), largest=False) == 0


def test_members_equal_to_the_solves_convergence_name_the_first():
    """Mirror edges of a symmetric roof solved to its tolerance differ by about 2e-9
    (measured on a hypar): the first is named, whichever came out larger. A difference of
    1e-6 is the structure's, not the solve's: the larger is named."""
    values = np.array([1.0, 3.0, 3.0 * (1 + 2e-9), 2.0])
    assert first_extreme(values, np.arange(4)) == 1
    values[2] = 3.0 * (1 + 1e-6)
    assert first_extreme(values, np.arange(4)) == 2


def test_an_infinite_extreme_names_its_first_member():
    """inf - inf is NaN: the tie test alone would name nothing (an IndexError)."""
    values = np.array([1.0, math.inf, 2.0, math.inf])
    assert first_extreme(values, np.arange(4)) == 1
    assert first_extreme(-values, np.arange(4), largest=False) == 1
