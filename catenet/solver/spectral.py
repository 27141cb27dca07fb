"""The spectral analysis of the time integrators (catenet/solver/integrators.py) on one
oscillator: the matrix that takes a scheme's state to the next (``amplification``) and the
damping ratio and period error it adds to an undamped mode (``numerical_damping``), as
tests/solver/test_integrators.py and benchmarks/integrators.py measure them."""

from __future__ import annotations

import math

import numpy as np

from catenet.solver.integrators import RHO_INF, Newmark, make


def amplification(
    name: str, h_omega: float, xi: float = 0.0, rho_inf: float = RHO_INF
) -> np.ndarray:
    """The matrix taking a scheme's state to the next for one oscillator
    x'' + 2 xi omega x' + omega^2 x = 0 at step h omega, with omega = 1 and h = h omega:
    (x, v) for implicit Euler, (x, v, a) for newmark (its spectral analysis: the principal
    eigenvalues give the numerical damping and period error, the others the dissipation of
    the unresolved modes)."""
    s, z = float(h_omega), float(xi)
    if name == "implicit_euler":
        # (1 + 2 z s + s^2) v1 = v0 - s x0; x1 = x0 + s v1
        d = 1.0 + 2.0 * z * s + s * s
        v_x, v_v = -s / d, 1.0 / d
        return np.array([[1.0 + s * v_x, s * v_v], [v_x, v_v]])
    nm = make(name, rho_inf)
    assert isinstance(nm, Newmark)  # (implicit Euler's is above; newmark's the other)
    out = np.empty((3, 3))
    for col, (x0, v0, a0) in enumerate(np.eye(3)):
        p = x0 + s * v0 + s * s * (0.5 - nm.beta) * a0
        # (1 - am) a1 + am a0 + 2 z v1 + x1 = 0 with x1 = p + beta s^2 a1 and
        # v1 = v0 + s ((1 - gamma) a0 + gamma a1)
        lhs = (1.0 - nm.alpha_m) + 2.0 * z * s * nm.gamma + nm.beta * s * s
        rhs = -(nm.alpha_m * a0 + 2.0 * z * (v0 + s * (1.0 - nm.gamma) * a0) + p)
        a1 = rhs / lhs
        v1 = v0 + s * ((1.0 - nm.gamma) * a0 + nm.gamma * a1)
        out[:, col] = (p + nm.beta * s * s * a1, v1, a1)
    return out


def numerical_damping(name: str, h_omega: float, rho_inf: float = RHO_INF) -> tuple[float, float]:
    """(damping ratio, relative period error) that the scheme adds to an undamped mode at
    step h omega: from its principal eigenvalues r exp(+-i Omega h),
    xi = -ln(r) / (Omega h) and T_numerical / T - 1 = h omega / (Omega h) - 1; for an
    overdamped (real) principal root the ratio is 1 and the period infinite."""
    lam = np.linalg.eigvals(amplification(name, h_omega, 0.0, rho_inf))
    pair = lam[np.abs(lam.imag) > 1e-14]
    if pair.size == 0:
        return 1.0, math.inf
    top = pair[np.argmax(np.abs(pair))]
    angle = abs(math.atan2(top.imag, top.real))
    return -math.log(abs(top)) / angle, h_omega / angle - 1.0
