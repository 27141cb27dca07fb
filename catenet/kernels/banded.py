"""A bordered band's Cholesky factorisation and solves (``catenet.solver.banded``), and
the reverse Cuthill-McKee order that makes a net's matrix a band.

Storage: the band's lower triangle by rows, ``L[j, d]`` = entry (j + d, j) for
d = 0 .. p (row j of the array holds column j of the matrix, contiguous in d); the
border C (n1, nb) and D (nb, nb, lower triangle) dense. The factors overwrite them:
L the band's Cholesky factor, C the block Y = L^-1 C, D the Cholesky factor of the Schur
complement D - Y^T Y. No LAPACK: plain loops, which for the narrow bands of a net cost
what LAPACK's unblocked band routine costs, without importing SciPy.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def cuthill_mckee(indptr, indices):
    """The reverse Cuthill-McKee order of a symmetric pattern (CSR of both triangles):
    each component from a node of least degree at the end of a breadth-first search
    (a pseudo-peripheral start), neighbours visited by increasing degree."""
    n = indptr.shape[0] - 1
    degree = np.empty(n, dtype=np.int64)
    for i in range(n):  # np.diff(indptr), without its costly compile
        degree[i] = indptr[i + 1] - indptr[i]
    order = np.empty(n, dtype=np.int64)
    seen = np.zeros(n, dtype=np.bool_)
    level = np.empty(n, dtype=np.int64)
    count = 0
    while count < n:
        start = -1
        for i in range(n):  # the unvisited node of least degree
            if not seen[i] and (start < 0 or degree[i] < degree[start]):
                start = i
        for _ in range(2):  # a breadth-first search from it: its last node of least degree
            level[:] = -1
            level[start] = 0
            queue = [start]
            head = 0
            last = start
            while head < len(queue):
                u = queue[head]
                head += 1
                for k in range(indptr[u], indptr[u + 1]):
                    w = indices[k]
                    if level[w] < 0:
                        level[w] = level[u] + 1
                        queue.append(w)
                        if level[w] > level[last] or (
                            level[w] == level[last] and degree[w] < degree[last]
                        ):
                            last = w
            start = last
        seen[start] = True
        first = count
        order[count] = start
        count += 1
        head = first
        while head < count:
            u = order[head]
            head += 1
            begin = count
            for k in range(indptr[u], indptr[u + 1]):
                w = indices[k]
                if not seen[w]:
                    seen[w] = True
                    order[count] = w
                    count += 1
            for a in range(begin + 1, count):  # by degree (insertion sort: few each)
                w = order[a]
                b = a - 1
                while b >= begin and degree[order[b]] > degree[w]:
                    order[b + 1] = order[b]
                    b -= 1
                order[b + 1] = w
    return order[::-1].copy()


@njit(cache=True)
def band_cholesky(L, C, D):
    """Factorises the bordered band in place (module docstring); False where a pivot is
    not positive (the matrix is not positive definite). Right-looking, the trailing
    rows updated by each column in turn (contiguous rows of L); the border's rows below
    its first non-zero row only (those above stay zero in Y)."""
    n1, w = L.shape
    p = w - 1
    for j in range(n1):
        piv = L[j, 0]
        if not piv > 0.0:
            return False
        piv = np.sqrt(piv)
        L[j, 0] = piv
        m = min(p, n1 - 1 - j)
        inv = 1.0 / piv
        for d in range(1, m + 1):
            L[j, d] *= inv
        for d in range(1, m + 1):
            v = L[j, d]
            if v != 0.0:
                jd = j + d
                for e in range(d, m + 1):
                    L[jd, e - d] -= L[j, e] * v
    nb = D.shape[0]
    if nb == 0:
        return True
    first = n1  # the first row of C with a non-zero entry
    for j in range(n1):
        for c in range(nb):
            if C[j, c] != 0.0:
                first = j
                break
        if first < n1:
            break
    for j in range(first, n1):  # Y = L^-1 C, row by row (all its columns at once)
        inv = 1.0 / L[j, 0]
        for c in range(nb):
            C[j, c] *= inv
        for d in range(1, min(p, n1 - 1 - j) + 1):
            v = L[j, d]
            if v != 0.0:
                jd = j + d
                for c in range(nb):
                    C[jd, c] -= v * C[j, c]
    for j in range(first, n1):  # S = D - Y^T Y (lower), then its Cholesky factor
        for a in range(nb):
            y = C[j, a]
            if y != 0.0:
                for b in range(a + 1):
                    D[a, b] -= y * C[j, b]
    for j in range(nb):
        s = D[j, j]
        for k in range(j):
            s -= D[j, k] * D[j, k]
        if not s > 0.0:
            return False
        D[j, j] = np.sqrt(s)
        for i in range(j + 1, nb):
            t = D[i, j]
            for k in range(j):
                t -= D[i, k] * D[j, k]
            D[i, j] = t / D[j, j]
    return True


@njit(cache=True)
def band_solve(L, Y, R, order, b):
    """The solution of the factorised system for b (in the original order)."""
    n1, w = L.shape
    p = w - 1
    nb = R.shape[0]
    n = n1 + nb
    z = np.empty(n)
    for i in range(n):
        z[i] = b[order[i]]
    for j in range(n1):  # L z1 = b1
        z[j] /= L[j, 0]
        v = z[j]
        if v != 0.0:
            for d in range(1, min(p, n1 - 1 - j) + 1):
                z[j + d] -= L[j, d] * v
    if nb:
        for a in range(nb):  # b2 - Y^T z1, then R R^T z2 = it
            s = z[n1 + a]
            for j in range(n1):
                s -= Y[j, a] * z[j]
            z[n1 + a] = s
        for i in range(nb):
            s = z[n1 + i]
            for k in range(i):
                s -= R[i, k] * z[n1 + k]
            z[n1 + i] = s / R[i, i]
        for i in range(nb - 1, -1, -1):
            s = z[n1 + i]
            for k in range(i + 1, nb):
                s -= R[k, i] * z[n1 + k]
            z[n1 + i] = s / R[i, i]
        for j in range(n1):  # z1 - Y z2
            s = 0.0
            for a in range(nb):
                s += Y[j, a] * z[n1 + a]
            z[j] -= s
    for j in range(n1 - 1, -1, -1):  # L^T x1 = z1
        s = z[j]
        for d in range(1, min(p, n1 - 1 - j) + 1):
            s -= L[j, d] * z[j + d]
        z[j] = s / L[j, 0]
    x = np.empty(n)
    for i in range(n):
        x[order[i]] = z[i]
    return x
