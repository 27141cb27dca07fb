"""Numba kernels: module-level @njit(cache=True) functions over flat contiguous arrays.

One module per physical term (``stretch``) plus the sparse scatter used by assembly.
``NUMBA_DISABLE_JIT=1`` runs them as plain Python for tracebacks.
"""
