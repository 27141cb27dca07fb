"""The added mass of water in natural modes (``added``: Ca rho_w A l0 per edge, moving
with the edge's ends sideways only): a taut string in water, its lateral frequencies
scaled by sqrt(m / (m + Ca rho_w A)), the axial ones unchanged, along an oblique axis
(M then has full 3 x 3 blocks) by the dense solver and by shift-invert Lanczos with
K - sigma M; the case keys material.added_mass and material.water_density."""

from __future__ import annotations

import math

import numpy as np
import pytest

from catenet.model.builders import Material, cable
from catenet.model.net import Loads
from catenet.scene import Scene
from catenet.solver.modes import natural_modes
from catenet.solver.path import Settings, workspace

RHO, AREA, EA, T = 7850.0, 1e-4, 2e7, 5000.0  # steel wire, N
RHO_W, CA = 1025.0, 1.0


def string(edges: int, axis) -> object:
    """A straight string of stretched length 10 m along ``axis``, tension T."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    end = 10.0 * axis
    material = Material(EA=EA, line_density=RHO * AREA)
    return cable([0, 0, 0], end.tolist(), edges + 1, material, length=10.0 / (1 + T / EA))


@pytest.mark.parametrize("edges, method", [(40, "dense"), (200, "lanczos")])
def test_string_in_water_lateral_scaled_axial_unchanged(edges, method):
    """Each node's added mass Ca rho_w A l0 (I - t t^T) (its two half edges, t the
    string's direction) multiplies the lateral mass of every node by the same factor
    (m + m_a) / m, m = rho A l0 per edge: the lateral modes' omega^2 by m / (m + m_a)
    exactly (the same shapes), the axial ones (along t: no added mass) unchanged; and
    the continuum's f_n = n / (2 L) sqrt(T / (mu + Ca rho_w A)) in the limit."""
    net = string(edges, [1.0, 2.0, -0.7])
    ws = workspace(Scene(net, Loads()), Settings())
    added = CA * RHO_W * AREA * net.rest_length
    dry = natural_modes(ws, net.nodes, 12, method=method)
    wet = natural_modes(ws, net.nodes, 12, method=method, added=added)
    t = (net.nodes[-1] - net.nodes[0]) / np.linalg.norm(net.nodes[-1] - net.nodes[0])
    ratio = RHO / (RHO + CA * RHO_W)

    def axial(modes):
        along = np.abs(np.einsum("knd,d->kn", modes.shape, t)).sum(axis=1)
        return along > 0.5 * np.abs(modes.shape).sum(axis=(1, 2))

    lateral_dry = dry.omega2[~axial(dry)]
    lateral_wet = wet.omega2[~axial(wet)]
    n = min(lateral_dry.size, lateral_wet.size)
    assert n >= 8
    assert np.allclose(lateral_wet[:n], ratio * lateral_dry[:n], rtol=1e-9)
    if axial(dry).any() and axial(wet).any():
        assert np.allclose(wet.omega2[axial(wet)][0], dry.omega2[axial(dry)][0], rtol=1e-9)
    # the continuum: f_1 = 1 / (2 L) sqrt(T / mu_wet), mu per stretched length
    eps = T / EA
    mu = (RHO * AREA + CA * RHO_W * AREA) / (1 + eps)
    f1 = 1 / 20.0 * math.sqrt(T / mu)
    assert wet.frequency[0] == pytest.approx(f1, rel=2.0 / edges**2)
    # M-orthonormal with the whole M, the participation counts the water sideways
    assert wet.stats["residual"] < 1e-8
    assert np.all(wet.total_mass > dry.total_mass)


def test_an_axial_mode_is_unchanged():
    """Enough modes to reach the first axial one (f = sqrt(EA / (rho A)) / (2 L0)):
    with and without the water, the same frequency."""
    net = string(20, [0.0, 1.0, 1.0])
    ws = workspace(Scene(net, Loads()), Settings())
    added = CA * RHO_W * AREA * net.rest_length
    every = 3 * 19
    dry = natural_modes(ws, net.nodes, every, method="dense")
    wet = natural_modes(ws, net.nodes, every, method="dense", added=added)
    t = np.array([0.0, 1.0, 1.0]) / math.sqrt(2)

    def first_axial(modes):
        along = np.abs(np.einsum("knd,d->kn", modes.shape, t)).sum(axis=1)
        k = int(np.argmax(along > 0.5 * np.abs(modes.shape).sum(axis=(1, 2))))
        return modes.omega2[k]

    assert first_axial(wet) == pytest.approx(first_axial(dry), rel=1e-10)


def test_tangential_added_mass_scales_the_axial_modes():
    """``added`` (E, 2): ca_n sideways and ca_t along each edge: the axial modes' omega^2
    scale by m / (m + ca_t rho_w A), the lateral ones by m / (m + ca_n rho_w A), each
    exactly (the string is straight: the blocks split the two directions)."""
    net = string(20, [0.0, 1.0, 1.0])
    ws = workspace(Scene(net, Loads()), Settings())
    water = RHO_W * AREA * net.rest_length
    ca_n, ca_t = 1.0, 0.4
    every = 3 * 19
    dry = natural_modes(ws, net.nodes, every, method="dense")
    wet = natural_modes(
        ws, net.nodes, every, method="dense", added=np.column_stack([ca_n * water, ca_t * water])
    )
    t = np.array([0.0, 1.0, 1.0]) / math.sqrt(2)

    def split(modes):
        along = np.abs(np.einsum("knd,d->kn", modes.shape, t)).sum(axis=1)
        axial = along > 0.5 * np.abs(modes.shape).sum(axis=(1, 2))
        return modes.omega2[axial], modes.omega2[~axial]

    (ax_dry, lat_dry), (ax_wet, lat_wet) = split(dry), split(wet)
    assert ax_dry.size >= 3 and ax_wet.size == ax_dry.size
    assert np.allclose(ax_wet, ax_dry * RHO / (RHO + ca_t * RHO_W), rtol=1e-9)
    n = min(lat_dry.size, lat_wet.size)
    assert np.allclose(lat_wet[:n], lat_dry[:n] * RHO / (RHO + ca_n * RHO_W), rtol=1e-9)
