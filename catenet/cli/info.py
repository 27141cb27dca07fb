"""``catenet info``: versions, linear-solver backend, threads and the JIT cache."""

from __future__ import annotations

import click

from catenet.cli.common import HELP, errors_to_exit_codes, setup_logging, verbosity_options


@click.command(name="info", context_settings=HELP)
@verbosity_options
def command(quiet: bool, verbose: int, debug: bool) -> None:
    """Print the versions of catenet and its libraries, the linear-solver backend that
    solver.linear = "auto" picks, the MKL and Numba thread counts and where Numba keeps
    its compiled kernels."""
    setup_logging(quiet, verbose, debug)
    with errors_to_exit_codes(debug):
        rows = collect()
        width = max(len(k) for k, _ in rows)
        for key, value in rows:
            click.echo(f"{key:<{width}}  {value}")


def collect() -> list[tuple[str, str]]:
    """(label, value) rows of ``catenet info``."""
    import sys

    import numba

    from catenet.output import environment
    from catenet.solver import linear as linsolve

    env = environment()
    rows = [("catenet", env["catenet"]), ("python", f"{env['python']} ({sys.executable})")]
    for name in ("numpy", "scipy", "numba", "h5py", "click", "pypardiso"):
        rows.append((name, env[name] or "not installed"))
    rows.append(("hdf5", env["hdf5"] or "unknown"))

    mkl_version, mkl_threads, pardiso_error = "", "", ""
    if linsolve.pardiso_available():
        lib = linsolve._load_pardiso().libmkl
        mkl_version = _mkl_version_string(lib) or env["mkl"]
        try:
            mkl_threads = str(int(lib.MKL_Get_Max_Threads()))
        except (AttributeError, OSError):
            mkl_threads = "unknown"
    else:
        pardiso_error = _pardiso_error()
    rows.append(("mkl", mkl_version or env["mkl"] or "not available"))
    backend = linsolve.resolve_backend("auto")
    if backend == "pardiso":
        rows.append(("linear backend", "PARDISO (MKL, via pypardiso)"))
    else:
        why = f": {pardiso_error}" if pardiso_error else ""
        rows.append(("linear backend", f"SciPy SuperLU (PARDISO not available{why})"))
    rows.append(("mkl threads", mkl_threads or "-"))
    rows.append(
        ("numba threads", f"{numba.get_num_threads()} (of {numba.config.NUMBA_NUM_THREADS})")
    )
    rows.append(("numba cache", _numba_cache()))
    return rows


def _mkl_version_string(lib) -> str:
    """MKL's own version string, through the library pypardiso loaded."""
    import ctypes

    try:
        buf = ctypes.create_string_buffer(256)
        lib.MKL_Get_Version_String(buf, ctypes.c_int(len(buf)))
        return buf.value.decode("ascii", "replace").strip()
    except (AttributeError, OSError):
        return ""


def _pardiso_error() -> str:
    try:
        from catenet.solver import linear as linsolve

        linsolve._load_pardiso()
    except Exception as exc:
        return f"{type(exc).__name__}: {exc}"
    return ""


def _numba_cache() -> str:
    """Where ``@njit(cache=True)`` kernels are stored: NUMBA_CACHE_DIR, else __pycache__
    beside the kernel modules."""
    from pathlib import Path

    import numba

    if numba.config.CACHE_DIR:
        return f"{numba.config.CACHE_DIR} (NUMBA_CACHE_DIR)"
    import catenet.kernels

    return str(Path(catenet.kernels.__file__).parent / "__pycache__")
