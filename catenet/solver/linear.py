"""Sparse direct solvers behind one interface: PARDISO (MKL) and SciPy.

PARDISO runs its three phases separately: symbolic analysis (11) once per sparsity
pattern, numeric factorisation (22) per Newton iteration, solve (33) per right-hand side.
pypardiso's public ``solve`` re-analyses whenever the values change, so this module calls
MKL's ``pardiso`` routine itself, with the argument types pypardiso declares, on arrays it
prepares once. pypardiso stays the dependency that installs MKL (the ``mkl`` wheel), but
it is not imported: its import builds a solver that searches the file system for
``mkl_rt`` (ldconfig, a recursive glob of sys.prefix). ``mkl_runtime`` finds the library
once, directly: ``$CATENET_MKL_RT`` (or pypardiso's ``$PYPARDISO_MKL_RT``) when set, else
the ``mkl`` wheel's ``lib`` directory under sys.prefix (or the user base), else the
dynamic loader's search path. Where MKL is absent, ``solver.linear = "auto"`` falls back
to SciPy with one warning and ``"pardiso"`` is refused with the places searched.

Every solve is checked: finite values, a small backward error and, for PARDISO, no
perturbed pivots. A failing check raises SingularSystemError naming the nodes concerned.
"""

from __future__ import annotations

import ctypes
import functools
import glob
import logging
import math
import os
import sys
import time
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from catenet.errors import ConfigError, SingularSystemError
from catenet.kernels.sparse import backward_error, csr_matvec

if TYPE_CHECKING:
    from scipy.sparse.linalg import SuperLU

log = logging.getLogger(__name__)

BACKWARD_ERROR_TOL = 1e-9
BACKENDS = ("auto", "pardiso", "scipy")
MKL_ENV = "CATENET_MKL_RT"  # path of MKL's runtime library (libmkl_rt), overrides the search
_MKL_ENVS = (MKL_ENV, "PYPARDISO_MKL_RT")
# The runtime's names: Linux (the mkl wheel ships .so.2 or .so.3), macOS, Windows.
_MKL_NAMES = ("libmkl_rt.so.3", "libmkl_rt.so.2", "libmkl_rt.so", "libmkl_rt.2.dylib",
              "libmkl_rt.dylib", "mkl_rt.2.dll", "mkl_rt.dll")  # fmt: skip


class MklNotFound(ImportError):
    """MKL's runtime library could not be loaded (the message says where it was sought)."""


class MklRuntime:
    """MKL's runtime library, loaded once: ``libmkl`` (the ctypes library), ``path``
    (where it was found) and its ``pardiso`` routine with pypardiso's argument types."""

    def __init__(self, lib: ctypes.CDLL, path: str):
        self.libmkl = lib
        self.path = path
        wide = ctypes.sizeof(ctypes.c_void_p) == 8  # PARDISO's handle: 64 pointers
        self._pt_type = (ctypes.c_int64, np.int64) if wide else (ctypes.c_int32, np.int32)
        i32 = ctypes.POINTER(ctypes.c_int32)
        fn = lib.pardiso
        p = ctypes.c_void_p  # arrays by address (PardisoSolver._pardiso)
        fn.argtypes = [p, i32, i32, i32, i32, i32, p, p, p, p, i32, p, i32, p, p, i32]
        fn.restype = None
        self._mkl_pardiso = fn


def mkl_candidates() -> tuple[str | None, list[str]]:
    """(the override variable that is set or None, the paths to try in order). Without
    an override: the library files in the ``lib`` (``Library/bin`` on Windows) directory
    of sys.prefix, the base prefix and the user base, then the bare names, which the
    dynamic loader looks up on its own search path (LD_LIBRARY_PATH, ld.so.cache)."""
    for var in _MKL_ENVS:
        value = os.environ.get(var, "").strip()
        if value:
            return var, [value]
    import site

    roots = []
    for prefix in (sys.prefix, sys.base_prefix, getattr(site, "USER_BASE", None)):
        if prefix and prefix not in roots:
            roots.append(prefix)
    paths = []
    for root in roots:
        for sub in ("lib", os.path.join("Library", "bin")):
            folder = os.path.join(root, sub)
            names = set(os.listdir(folder)) if os.path.isdir(folder) else set()
            paths += [os.path.join(folder, n) for n in _MKL_NAMES if n in names]
            # Other versions (libmkl_rt.so.4, ...), the highest first.
            extra = sorted(glob.glob(os.path.join(glob.escape(folder), "*mkl_rt*")), reverse=True)
            paths += [p for p in extra if p not in paths and not p.endswith((".a", ".lib"))]
    return None, paths + list(_MKL_NAMES)


@functools.cache
def _find_mkl(key: tuple[str, ...]) -> MklRuntime | MklNotFound:
    """The runtime (or why it is missing), once per override setting."""
    var, paths = mkl_candidates()
    errors = []
    for path in paths:
        try:
            lib = ctypes.CDLL(path)
            lib.pardiso  # noqa: B018  (an mkl_rt without PARDISO is no use)
        except (OSError, AttributeError) as exc:
            errors.append(f"{path}: {exc}")
            continue
        log.debug("MKL runtime: %s", path)
        return MklRuntime(lib, path)
    if var is not None:
        return MklNotFound(
            f"{var} = {paths[0]!r}: MKL's runtime library cannot be loaded from there "
            f"({errors[0] if errors else 'not found'}); point it to libmkl_rt (e.g. "
            f"{os.path.join(sys.prefix, 'lib', _MKL_NAMES[0])}) or unset it"
        )
    return MklNotFound(
        f"MKL's runtime library (libmkl_rt) was not found in {sys.prefix}/lib or on the "
        f"loader's path: install it (pip install mkl, or pypardiso) or set {MKL_ENV} to "
        "its path"
    )


def mkl_runtime() -> MklRuntime:
    """MKL's runtime library, found and loaded once per process; raises MklNotFound."""
    found = _find_mkl(tuple(os.environ.get(v, "") for v in _MKL_ENVS))
    if isinstance(found, MklNotFound):
        raise MklNotFound(str(found))
    return found


def mkl_problem() -> str:
    """Why MKL's runtime cannot be used ('' where it can)."""
    found = _find_mkl(tuple(os.environ.get(v, "") for v in _MKL_ENVS))
    return str(found) if isinstance(found, MklNotFound) else ""


def pardiso_available() -> bool:
    return not mkl_problem()


_load_pardiso = mkl_runtime  # (the old name)


_warned: set[str] = set()


def resolve_backend(name: str) -> str:
    """'auto' -> 'pardiso' where MKL loads, else 'scipy'."""
    if name not in BACKENDS:
        raise ConfigError(f"solver.linear = {name!r}: must be one of {', '.join(BACKENDS)}")
    if name == "scipy":
        return name
    if pardiso_available():
        return "pardiso"
    why = mkl_problem() or "MKL's runtime library could not be used"
    if name == "pardiso":
        raise ConfigError(
            f"solver.linear = 'pardiso': MKL is not available on this machine: {why}; "
            "use 'auto' or 'scipy'"
        )
    if why not in _warned:  # once per process (and per override)
        _warned.add(why)
        log.warning("%s: solving with SciPy's SuperLU instead of PARDISO (slower)", why)
    return "scipy"


class LinearSolver:
    """Solves A x = b for a fixed pattern (CSR ``indptr``, ``indices``) and changing values.

    ``upper``: the pattern holds the upper triangle of a symmetric matrix.
    ``dof_node``: node index of every row, to name nodes in errors.
    """

    name = "base"
    mtype: int | None = None  # PARDISO's matrix type (None: another backend)

    def __init__(self, indptr: ArrayLike, indices: ArrayLike, *, upper: bool, dof_node: np.ndarray):
        self.indptr = np.ascontiguousarray(indptr, dtype=np.int32)
        self.indices = np.ascontiguousarray(indices, dtype=np.int32)
        self.n = len(self.indptr) - 1
        self.upper = upper
        self.dof_node = dof_node
        self._data: np.ndarray | None = None  # the values last factorised (a copy)
        self._anorm = 0.0
        self._r = np.empty(self.n)
        self._analysed = False
        self._checked = False  # the last factorisation's first solve passed its check
        self.stats = {"analyse": 0, "factorize": 0, "solve": 0}
        self.seconds = {"analyse": 0.0, "factorize": 0.0, "solve": 0.0}

    def factorize(self, data: np.ndarray, definite: bool = False) -> None:
        """Factorises the matrix with values ``data``. ``definite``: the caller knows it
        is positive semidefinite (only convex terms filled it), so a backend set up for
        symmetric indefinite matrices may use Cholesky for this one."""
        self._select(definite)
        # A copy: a kept factorisation (modified Newton) is checked against the matrix it
        # was factorised from, not against the caller's array refilled since.
        if self._data is None or self._data.shape != data.shape:
            self._data = np.empty_like(data, dtype=np.float64)
        np.copyto(self._data, data)
        data = self._data
        self._anorm = float(np.max(np.abs(data), initial=0.0))
        if not math.isfinite(self._anorm):
            raise SingularSystemError(
                "the system matrix has non-finite entries", nodes=self._nodes(~np.isfinite(data))
            )
        if not self._analysed:
            self.analyse(data)
        start = time.perf_counter()
        self._checked = False
        self._factorize(data)
        self.seconds["factorize"] += time.perf_counter() - start
        self.stats["factorize"] += 1

    def solve(self, b: np.ndarray) -> np.ndarray:
        """A^-1 b. The first solve after each factorisation checks its backward error
        (refining where it is too large, raising SingularSystemError where that fails):
        factors that pass are accurate, so later solves with them (modified Newton's kept
        factorisation) check only that the result is finite."""
        start = time.perf_counter()
        x = self._solve(b)
        if self._checked:
            if not np.all(np.isfinite(x)):
                self._check(b, x)  # raises, naming the nodes
        else:
            try:
                self._check(b, x)
                self._checked = True  # (factors that needed refinement are checked again)
            except SingularSystemError:
                if not self._refine(b, x):
                    raise
                self._check(b, x)
        self.seconds["solve"] += time.perf_counter() - start
        self.stats["solve"] += 1
        return x

    def solve_many(self, b: np.ndarray) -> np.ndarray:
        """A^-1 b for the columns of b (n, k), unchecked (as solve_unchecked)."""
        return np.column_stack([self._solve(np.ascontiguousarray(c)) for c in b.T])

    def solve_unchecked(self, b: np.ndarray) -> np.ndarray:
        """A^-1 b with the factors as they are, unchecked: for a caller that refines the
        result on a matrix of its own (the factors are of a scaled or nearby one)."""
        start = time.perf_counter()
        x = self._solve(b)
        self.seconds["solve"] += time.perf_counter() - start
        self.stats["solve"] += 1
        return x

    def _refine(self, b: np.ndarray, x: np.ndarray, steps: int = 3) -> bool:
        """Iterative refinement in place: x += A^-1 (b - A x), a few times. False where
        the solution is not finite (nothing to refine)."""
        if not np.all(np.isfinite(x)):
            return False
        for _ in range(steps):
            csr_matvec(self.indptr, self.indices, self._data, x, self.upper, self._r)
            x += self._solve(b - self._r)
        self.stats["refine"] = self.stats.get("refine", 0) + 1
        return True

    # --- checks --------------------------------------------------------------------------
    def _check(self, b: np.ndarray, x: np.ndarray) -> None:
        x = np.asarray(x, dtype=np.float64)
        err = float(
            backward_error(self.indptr, self.indices, self._data, self._anorm, x,
                           np.asarray(b, dtype=np.float64), self.upper, self._r)
        )  # fmt: skip
        if err < 0.0:
            raise SingularSystemError(
                "the linear solve gave non-finite values (a mechanism or an all-slack region)",
                nodes=self._node_list(np.flatnonzero(~np.isfinite(x))),
            )
        if err > BACKWARD_ERROR_TOL:
            worst = np.argsort(-np.abs(self._r))[:10]
            raise SingularSystemError(
                f"the linear solve is inaccurate (backward error {err:.1e}): the system is "
                "singular or nearly so (a mechanism or an all-slack region)",
                nodes=self._node_list(worst),
            )

    def weak_nodes(self) -> list[int]:
        """Nodes whose DOFs have (almost) no stiffness on the diagonal."""
        diag = np.zeros(self.n)
        if self._data is None:  # nothing factorised yet
            return []
        rows = np.repeat(np.arange(self.n), np.diff(self.indptr))
        on = rows == self.indices
        diag[rows[on]] = self._data[on]
        weak = np.flatnonzero(diag <= 1e-12 * max(self._anorm, 1e-300))
        return self._node_list(weak)

    def _nodes(self, mask_data: ArrayLike) -> list[int]:
        rows = np.repeat(np.arange(self.n), np.diff(self.indptr))
        return self._node_list(rows[np.asarray(mask_data)])

    def _node_list(self, dofs: ArrayLike) -> list[int]:
        return sorted({int(self.dof_node[d]) for d in np.asarray(dofs).ravel()})[:20]

    def analyse(self, data: np.ndarray) -> None:
        """Symbolic analysis of the pattern (a no-op where the backend has none)."""
        self._analysed = True

    def _select(self, definite: bool) -> None:
        """Chooses the factorisation for the next matrix (see ``factorize``)."""

    def negative_eigenvalues(self) -> int | None:
        """Negative eigenvalues of the last factorised matrix, where the factorisation
        tells (symmetric indefinite), else None."""
        return None

    def _factorize(self, data: np.ndarray) -> None:
        raise NotImplementedError

    def _solve(self, b: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def release(self) -> None:
        """Free the factorisation."""


class PardisoSolver(LinearSolver):
    """MKL PARDISO. ``mtype``: 2 (SPD), -2 (symmetric indefinite), 11 (general).

    With mtype -2, a matrix the caller calls definite (``factorize(definite=True)``: an
    obstacle's non-convex term is out of reach) is factorised by Cholesky (mtype 2) in a
    second PARDISO handle with its own symbolic analysis, made once: a scene with an idle
    obstacle costs what the same scene without it costs. ``kind`` is the type in use."""

    name = "pardiso"
    #: Perturbed pivots accepted (a saddle point's: the solves' backward-error check, with
    #: refinement, then decides); by default they mean a singular matrix.
    perturbed_ok = False

    def __init__(
        self,
        indptr: ArrayLike,
        indices: ArrayLike,
        *,
        upper: bool,
        dof_node: np.ndarray,
        mtype: int | None = None,
    ):
        super().__init__(indptr, indices, upper=upper, dof_node=dof_node)
        self.mtype: int = (-2 if upper else 11) if mtype is None else mtype
        if (self.mtype in (2, -2)) != upper:
            raise ValueError("symmetric PARDISO types need the upper triangle, 11 the full matrix")
        self._wrapper = mkl_runtime()
        self._call = self._wrapper._mkl_pardiso
        self.pt = np.zeros(64, dtype=self._wrapper._pt_type[1])  # PARDISO's handle, ours alone
        self.kind = self.mtype  # the type of the handle in use (2 for definite matrices)
        self._handles: dict[int, tuple[np.ndarray, bool]] = {}  # the other types' handles
        self._perm = np.zeros(0, dtype=np.int32)
        iparm = np.zeros(64, dtype=np.int32)
        iparm[0] = 1  # no solver defaults: every value below is ours
        iparm[1] = 2  # nested dissection (METIS) ordering
        iparm[7] = 0  # no iterative refinement: solve() refines only when its check fails
        iparm[9] = 8 if upper else 13  # pivot perturbation 1e-8 / 1e-13
        # No scaling or weighted matching: PARDISO computes them from the values in the
        # analysis phase, which runs once per pattern; they would be stale afterwards
        # (and wrong for good if the first matrix was singular, as at a flat start).
        iparm[10] = 0
        iparm[12] = 0
        iparm[17] = -1  # report nonzeros of the factors
        iparm[20] = 1  # Bunch-Kaufman pivoting for symmetric indefinite
        iparm[34] = 1  # zero-based indices: the CSR arrays are passed as they are
        self.iparm = iparm
        self._error = ctypes.c_int32(0)
        self._phase, self._mtype = ctypes.c_int32(0), ctypes.c_int32(0)
        self._c_one, self._c_zero, self._c_n = (ctypes.c_int32(v) for v in (1, 0, self.n))
        self._addresses: dict[int, tuple[np.ndarray, int]] = {}
        self._x = np.empty(self.n)
        self._b = np.empty(self.n)
        self._dummy = np.zeros(1)

    def _pardiso(self, phase: int, data: np.ndarray, b: np.ndarray, x: np.ndarray) -> None:
        # The call's arguments by address: the handle's, the pattern's and iparm's cached
        # per array, the scalars in ctypes integers kept for the purpose (a call at a small
        # system is mostly argument conversion otherwise).
        self._error.value = 0
        self._phase.value = phase
        self._mtype.value = self.kind
        self._call(
            self._address(self.pt), self._c_one, self._c_one, self._mtype, self._phase,
            self._c_n, data.ctypes.data, self._address(self.indptr),
            self._address(self.indices), self._address(self._perm), self._c_one,
            self._address(self.iparm), self._c_zero, b.ctypes.data, x.ctypes.data,
            self._error,
        )  # fmt: skip
        code = self._error.value
        if code != 0:
            nodes = self.weak_nodes() if self._data is not None else []
            if code in (-4, -7):  # zero pivot / diagonal matrix is singular
                raise SingularSystemError(
                    f"PARDISO: the system matrix is singular (error {code}): "
                    "a mechanism or an all-slack region",
                    nodes=nodes,
                )
            if code in (-2, -12):
                raise MemoryError(f"PARDISO ran out of memory (error {code})")
            raise SingularSystemError(
                f"PARDISO failed with error {code} in phase {phase}", nodes=nodes
            )

    def _address(self, a: np.ndarray) -> int:
        """The address of an array that stays (the handle, the pattern, iparm), once per
        array: the entry holds the array, so that its id names it for good."""
        held = self._addresses.get(id(a))
        if held is None or held[0] is not a:
            held = self._addresses[id(a)] = (a, a.ctypes.data)
        return int(held[1])

    def analyse(self, data: np.ndarray) -> None:
        """Symbolic analysis (ordering and fill-in) of the pattern, once."""
        start = time.perf_counter()
        self._pardiso(11, data, self._dummy, self._dummy)
        self._analysed = True
        self.seconds["analyse"] += time.perf_counter() - start
        self.stats["analyse"] += 1

    def _factorize(self, data: np.ndarray) -> None:
        self._pardiso(22, data, self._dummy, self._dummy)
        if self.iparm[13] > 0 and not self.perturbed_ok:  # perturbed: (nearly) singular
            raise SingularSystemError(
                f"PARDISO perturbed {int(self.iparm[13])} pivots: the system is singular or "
                "nearly so (a mechanism or an all-slack region)",
                nodes=self.weak_nodes(),
            )

    def _solve(self, b: np.ndarray) -> np.ndarray:
        assert self._data is not None  # factorize() came first
        np.copyto(self._b, b)
        x = np.empty(self.n)
        self._pardiso(33, self._data, self._b, x)
        return x

    def _select(self, definite: bool) -> None:
        kind = 2 if (definite and self.mtype == -2) else self.mtype
        if kind != self.kind:  # swap handles: each keeps its own symbolic analysis
            self._handles[self.kind] = (self.pt, self._analysed)
            fresh = (np.zeros(64, dtype=self._wrapper._pt_type[1]), False)
            self.pt, self._analysed = self._handles.pop(kind, fresh)
            self.kind = kind

    def negative_eigenvalues(self) -> int | None:
        if self.mtype != -2:
            return None
        return 0 if self.kind == 2 else int(self.iparm[22])  # Cholesky: positive definite

    @property
    def inertia(self) -> tuple[int, int]:
        """(positive, negative) eigenvalue counts of the last symmetric factorisation."""
        if self.kind == 2 and self.mtype == -2:
            return self.n, 0
        return int(self.iparm[21]), int(self.iparm[22])

    @property
    def factor_nnz(self) -> int:
        return int(self.iparm[17])

    def release(self) -> None:
        self._release()
        pt, kind = self.pt, self.kind
        for other, (handle, analysed) in list(self._handles.items()):  # the idle handles
            self.pt, self._analysed, self.kind = handle, analysed, other
            self._release()
            self._handles[other] = (handle, False)
        self.pt, self._analysed, self.kind = pt, False, kind

    def _release(self) -> None:
        if self._analysed:
            try:
                self._pardiso(-1, self._dummy, self._dummy, self._dummy)
            except Exception:  # releasing is best effort
                pass
            self._analysed = False

    def __del__(self) -> None:
        self.release()


class ScipySolver(LinearSolver):
    """SciPy's SuperLU: the fallback where MKL is missing (slower: no symbolic reuse)."""

    name = "scipy"

    def __init__(self, indptr: ArrayLike, indices: ArrayLike, *, upper: bool, dof_node: np.ndarray):
        super().__init__(indptr, indices, upper=upper, dof_node=dof_node)
        self._lu: SuperLU | None = None

    def _factorize(self, data: np.ndarray) -> None:
        import scipy.sparse as sp
        from scipy.sparse.linalg import splu

        a = sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))
        if self.upper:
            a = a + sp.triu(a, k=1).T
        try:  # symmetric mode: diagonal pivots keep the fill of a symmetric ordering
            self._lu = splu(
                a.tocsc(),
                permc_spec="MMD_AT_PLUS_A",
                diag_pivot_thresh=0.0,
                options={"SymmetricMode": True},
            )
        except RuntimeError as exc:  # "Factor is exactly singular"
            raise SingularSystemError(
                f"SciPy: {exc}: a mechanism or an all-slack region", nodes=self.weak_nodes()
            ) from None

    def _solve(self, b: np.ndarray) -> np.ndarray:
        assert self._lu is not None  # factorize() came first
        x: np.ndarray = self._lu.solve(np.asarray(b, dtype=np.float64))
        return x

    def negative_eigenvalues(self) -> int | None:
        """With symmetric pivoting (row order = column order) A = P' L U P and U's
        diagonal is the D of an LDL' factorisation: its signs are the inertia."""
        lu = self._lu
        if lu is None or not np.array_equal(lu.perm_r, lu.perm_c):
            return None
        return int(np.count_nonzero(lu.U.diagonal() < 0))

    def release(self) -> None:
        self._lu = None


def make_solver(
    backend: str,
    indptr: ArrayLike,
    indices: ArrayLike,
    *,
    upper: bool,
    dof_node: np.ndarray,
    mtype: int | None = None,
) -> LinearSolver:
    backend = resolve_backend(backend)
    if backend == "pardiso":
        return PardisoSolver(indptr, indices, upper=upper, dof_node=dof_node, mtype=mtype)
    return ScipySolver(indptr, indices, upper=upper, dof_node=dof_node)
