"""Scatter of element values into CSR data through a map built once per pattern."""

from __future__ import annotations

import math

from numba import njit


@njit(cache=True)
def scatter(values, target, data):
    """data[:] = 0; data[target[k]] += values[k] for every k with target[k] >= 0."""
    for p in range(data.shape[0]):
        data[p] = 0.0
    for k in range(values.shape[0]):
        p = target[k]
        if p >= 0:
            data[p] += values[k]


@njit(cache=True)
def add_diagonal(diag_pos, shift, data):
    """data[diag_pos[d]] += shift[d]: the mass and regularisation terms."""
    for d in range(diag_pos.shape[0]):
        data[diag_pos[d]] += shift[d]


@njit(cache=True)
def csr_matvec(indptr, indices, data, x, upper, out):
    """out = A x for CSR (indptr, indices, data); with ``upper`` the data hold the upper
    triangle of a symmetric A and the lower part is applied by symmetry."""
    n = indptr.shape[0] - 1
    for r in range(n):
        out[r] = 0.0
    for r in range(n):
        acc = 0.0
        for p in range(indptr[r], indptr[r + 1]):
            c = indices[p]
            acc += data[p] * x[c]
            if upper and c != r:
                out[c] += data[p] * x[r]
        out[r] += acc


@njit(cache=True)
def backward_error(indptr, indices, data, anorm, x, b, upper, r):
    """A solve's backward error max |A x - b| / (anorm max |x| + max |b|) (0 where that
    scale is 0), the residual A x - b left in r; -1 where x has a non-finite value."""
    x_max = 0.0
    for k in range(x.shape[0]):
        v = abs(x[k])
        if not v < math.inf:  # inf or nan
            return -1.0
        x_max = max(x_max, v)
    csr_matvec(indptr, indices, data, x, upper, r)
    b_max = 0.0
    r_max = 0.0
    for k in range(b.shape[0]):
        r[k] -= b[k]
        b_max = max(b_max, abs(b[k]))
        r_max = max(r_max, abs(r[k]))
    scale = anorm * x_max + b_max
    return r_max / scale if scale > 0 else 0.0


@njit(cache=True)
def dot(a, b):
    """a . b in one thread: BLAS would spawn threads for vectors this short, which costs
    more than it saves (much more on a loaded machine)."""
    total = 0.0
    for k in range(a.shape[0]):
        total += a[k] * b[k]
    return total


def norm(a) -> float:
    """The 2-norm of a, in one thread (see ``dot``): the same sum as a kernel of its own
    would do, one kernel fewer to compile and load."""
    return math.sqrt(dot(a, a))


@njit(cache=True)
def scatter_add(values, target, data):
    """data[target[k]] += values[k] for every k with target[k] >= 0."""
    for k in range(values.shape[0]):
        p = target[k]
        if p >= 0:
            data[p] += values[k]
