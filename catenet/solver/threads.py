"""How many threads the solve uses: MKL's (PARDISO), Numba's and every OpenBLAS's in the
process (``solver.threads``)."""

from __future__ import annotations

import ctypes
import os

from catenet.errors import ConfigError
from catenet.solver.linear import mkl_runtime, pardiso_available


def set_threads(threads: int) -> None:
    """Threads of MKL (PARDISO), Numba and every OpenBLAS loaded in this process (NumPy's
    and SciPy's: left alone, its spinning threads slow short vector operations down)."""
    if threads < 1:
        raise ConfigError(f"solver.threads = {threads}: must be >= 1")
    if pardiso_available():
        mkl_runtime().libmkl.MKL_Set_Num_Threads(ctypes.c_int(threads))
    set_numba_threads(threads, launch=False)
    os.environ["OPENBLAS_NUM_THREADS"] = str(threads)  # for an OpenBLAS loaded later
    for path in _openblas_libraries():
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        for name in (
            "scipy_openblas_set_num_threads64_",
            "scipy_openblas_set_num_threads",
            "openblas_set_num_threads64_",
            "openblas_set_num_threads",
        ):
            fn = getattr(lib, name, None)
            if fn is not None:
                fn(ctypes.c_int(threads))
                break


def set_numba_threads(threads: int, launch: bool = True) -> None:
    """Numba's thread count. ``launch=False``: only where its thread pool runs already.
    catenet's kernels are serial, so a run has no use for the pool, and starting it (its
    threading layer's library and threads) costs a whole ``catenet run`` about 1.5%."""
    import numba
    from numba.np.ufunc import parallel

    if launch or getattr(parallel, "_is_initialized", True):
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))


def _openblas_libraries() -> list[str]:
    """Paths of the OpenBLAS libraries mapped into this process (Linux; else none).
    SciPy's is not loaded for this (importing scipy.linalg costs 0.1-0.3 s of start-up):
    one loaded later reads OPENBLAS_NUM_THREADS, which ``set_threads`` sets."""
    import numpy  # noqa: F401  (loads NumPy's OpenBLAS)

    try:
        with open("/proc/self/maps") as fh:
            return sorted({ln.split()[-1] for ln in fh if "openblas" in ln.lower() and "/" in ln})
    except OSError:
        return []
