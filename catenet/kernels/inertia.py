"""The implicit step's inertia and damping: E = 1/2 sum_d w_d (x_d - a_d)^2 over DOFs d."""

from __future__ import annotations

from numba import njit


@njit(cache=True)
def inertia_gradient(x, dofs, w, a, grad):
    """Adds w (x - a) at ``dofs`` of the flat arrays x and grad; returns the energy."""
    total = 0.0
    for k in range(dofs.shape[0]):
        d = dofs[k]
        r = x[d] - a[k]
        grad[d] += w[k] * r
        total += 0.5 * w[k] * r * r
    return total


@njit(cache=True)
def inertia_roundoff(x, dofs, w, a):
    """Round-off levels of the gradient (|w (|x| + |a|)|) and of the energy (w.(x^2 + a^2))."""
    g2 = 0.0
    e = 0.0
    for k in range(dofs.shape[0]):
        xd = x[dofs[k]]
        s = w[k] * (abs(xd) + abs(a[k]))
        g2 += s * s
        e += w[k] * (xd * xd + a[k] * a[k])
    return g2**0.5, e
