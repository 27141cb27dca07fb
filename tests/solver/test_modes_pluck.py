"""The lowest frequency of ``catenet modes`` against a plucked net in an undamped
newmark run: the period read from the trajectory."""

from __future__ import annotations

import math

import numpy as np

import catenet
from catenet.solver.path import Settings, Start, solve


def test_plucked_paper_net_rings_at_the_lowest_frequency(tmp_path):
    """The paper's n = 10 net (contract §2: L = 1 m, edge 0.05 m, E = 10 MPa, r = 1 cm,
    rho = 1000 kg/m^3, p = 100 Pa) at its equilibrium under the pressure, displaced along
    its first mode (amplitude 1e-5 L: linear) and let go without damping. Small
    vibrations about the equilibrium obey M u'' + K u = 0, so the displaced mode rings
    at its own omega_1 alone. Newmark's average-acceleration rule (solver.integrator =
    "newmark", rho_inf = 1) integrates u'' = -omega^2 u without amplitude error and with
    the phase per step Omega h = 2 arctan(omega h / 2) (its amplification matrix has
    eigenvalues exp(+-i Omega h)): the period it shows is 2 pi / Omega, longer than
    2 pi / omega by (omega h)^2 / 12 to leading order. Read from the zero crossings of
    the most moving node's displacement over 6 periods (40 steps each), it matches
    2 pi / Omega to 1e-4 (the crossings are interpolated linearly; the error of each is
    O(h^3 omega^2), divided by the span of six periods).
    """
    from catenet.case import build, load_case

    path = tmp_path / "net.toml"
    path.write_text(
        """
[geometry]
kind = "square_net"
n = 10
alpha = 0.0
size = 1.0
edge_length = 0.05
[material]
E = 10e6
radius = 0.01
density = 1000.0
[load]
pressure = 100.0
"""
    )
    scene = build(load_case(path, ()))
    modes = catenet.modes(scene, k=1)
    omega = 2 * math.pi * modes.frequency[0]
    period = 2 * math.pi / omega
    h = period / 40
    node = int(np.argmax(np.abs(modes.shape[0]).max(axis=1)))
    axis = int(np.argmax(np.abs(modes.shape[0][node])))
    amplitude = 1e-5 / np.abs(modes.shape[0]).max()
    x0 = modes.x + amplitude * modes.shape[0]
    settings = Settings(
        method="dynamic", integrator="newmark", rho_inf=1.0, damping=0.0, dt=h,
        t_end=6.2 * period, rtol=1e-12,
    )  # fmt: skip
    times, disp = [0.0], [x0[node, axis] - modes.x[node, axis]]

    def seen(step) -> None:
        times.append(step.time)
        disp.append(step.x[node, axis] - modes.x[node, axis])

    solve(scene, settings, start=Start(x=x0, v=np.zeros_like(x0)), on_step=seen)
    t, u = np.array(times), np.array(disp)
    cross = np.flatnonzero((u[:-1] > 0) & (u[1:] <= 0))  # downward zero crossings
    at = t[cross] - u[cross] * (t[cross + 1] - t[cross]) / (u[cross + 1] - u[cross])
    measured = (at[-1] - at[0]) / (len(at) - 1)
    assert len(at) >= 6
    numerical = 2 * math.pi / (2 * math.atan(omega * h / 2) / h)
    assert abs(measured / numerical - 1) < 1e-4
    assert measured / period - 1 > 1e-3  # the integrator's elongation is resolved
    assert np.max(np.abs(u)) < 1.01 * abs(u[0])  # no growth: linear, undamped
