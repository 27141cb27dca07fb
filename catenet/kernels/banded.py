"""A bordered band's Cholesky factorisation and solves (``catenet.solver.banded``), and
the reverse Cuthill-McKee order that makes a net's matrix a band.

Storage: the band's lower triangle by rows, ``L[j, d]`` = entry (j + d, j) for
d = 0 .. p (row j of the array holds column j of the matrix, contiguous in d); the
border C (n1, nb) and D (nb, nb, lower triangle) dense. The factors overwrite them:
L the band's Cholesky factor, C the block Y = L^-1 C, D the Cholesky factor of the Schur
complement D - Y^T Y.

The band's factorisation is LAPACK's dpbtrf (``band_cholesky``: blocked, as SciPy
ships it; the array is its lower band storage in Fortran order, AB(1 + d, j) = L[j, d],
so it is passed as it is), or plain loops (``band_cholesky_loops``), which took 1.16x to
1.6x its time on the steps' matrices of benchmarks/solvers_small.py (384 to 1155
unknowns, half widths 32 to 56; docs/performance.md).
SciPy's LAPACK is reached by its address (``scipy.linalg.cython_lapack``), known to
LLVM under ``DPBTRF`` once ``lapack_ready`` has run, so that the kernel stays cached.
"""

from __future__ import annotations

import llvmlite.binding as llvm
import numpy as np
from numba import njit, types

DPBTRF = "catenet_dpbtrf"  # the symbol LAPACK's dpbtrf is known to LLVM by
_VOID = types.voidptr
_dpbtrf = types.ExternalFunction(DPBTRF, types.void(_VOID, _VOID, _VOID, _VOID, _VOID, _VOID))
_ready: list[bool] = []


def lapack_ready() -> bool:
    """Makes SciPy's dpbtrf known to LLVM (once); False where it cannot be found."""
    if not _ready:
        try:
            from numba.extending import get_cython_function_address

            address = get_cython_function_address("scipy.linalg.cython_lapack", "dpbtrf")
        except (ImportError, ValueError, AttributeError):
            _ready.append(False)
        else:
            llvm.add_symbol(DPBTRF, address)
            _ready.append(True)
    return _ready[0]


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
def band_cholesky(L, C, D, zero=0.0):
    """Factorises the bordered band in place (module docstring), the band by LAPACK's
    dpbtrf (``lapack_ready`` first); False where a pivot is not positive (the matrix is
    not positive definite, or not finite) or not above ``zero`` times the largest
    diagonal entry (a matrix singular to round-off, as PARDISO's pivots measure it)."""
    n1, w = L.shape
    if not L.flags.c_contiguous:  # (LAPACK reads the storage as it lies)
        return band_cholesky_loops(L, C, D, zero)
    least = zero * _largest(L, D)
    if n1:
        args = np.empty(4, dtype=np.int32)  # n, kd, ldab, info
        args[0], args[1], args[2], args[3] = n1, w - 1, w, 0
        lower = np.full(1, 76, dtype=np.uint8)  # "L"
        _dpbtrf(lower.ctypes, args[0:].ctypes, args[1:].ctypes, L.ctypes, args[2:].ctypes,
                args[3:].ctypes)  # fmt: skip
        if args[3] != 0:
            return False
        for j in range(n1):  # (dpbtrf passes a NaN pivot on)
            piv = L[j, 0] * L[j, 0]
            if not np.isfinite(piv) or not piv > least:
                return False
    return _border(L, C, D, least)


@njit(cache=True)
def _largest(L, D):
    """The largest diagonal entry of the bordered band (before its factorisation)."""
    out = 0.0
    for j in range(L.shape[0]):
        out = max(out, L[j, 0])
    for j in range(D.shape[0]):
        out = max(out, D[j, j])
    return out


@njit(cache=True)
def band_cholesky_loops(L, C, D, zero=0.0):
    """``band_cholesky`` by plain loops: right-looking, the trailing rows updated by
    each column in turn (contiguous rows of L)."""
    n1, w = L.shape
    p = w - 1
    least = zero * _largest(L, D)
    for j in range(n1):
        piv = L[j, 0]
        if not piv > max(least, 0.0):
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
    return _border(L, C, D, least)


@njit(cache=True)
def _border(L, C, D, least):
    """The border's factors after the band's (L factorised): Y = L^-1 C, over the rows
    below C's first non-zero row only (those above stay zero in Y), and the Cholesky
    factor of the Schur complement; False where it is not positive definite or a pivot is
    none (not above ``least``)."""
    n1, w = L.shape
    p = w - 1
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
        if not s > max(least, 0.0):
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
