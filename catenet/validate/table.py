"""catenet against the closed forms of ``catenet.validate.analytic``: the table of
``catenet validate``.

Two problems of the paper's Sec. 3.1, on the paper's cable (L = 1 m, E = 10 MPa, r = 1 cm,
density 1000 kg/m^3, so EA = 3141.6 N and w = rho A g = 3.082 N/m):

(i) Midpoint load (Eqs. 16-17). A cable of rest length L pinned a chord L apart, a
    downward force F on its midpoint node (odd node count), F/EA from 1e-4 up to the load
    of 5 % strain. The discrete model is exact for this problem (each half is a straight
    chain of equally strained edges), so the only error is the solver's: the tolerance is
    1e-9 relative at every resolution, with Newton at rtol = 1e-10.

(ii) Compressed catenary (Eqs. 14-15). The same cable under gravity, its supports moved
    inward by dL/2 each, dL/L in {0.05, 0.2, 0.5}, against the exact elastic catenary with
    the same EA and w (``analytic.elastic_catenary``): mid-span sag and horizontal support
    reaction H at N = 11, 21, 41, 81, 161 nodes. The model lumps the weight at the nodes
    (the trapezoidal rule) and replaces arcs by chords; both are second order in the edge
    length h, so the error is C (h/L)^2 + O(h^4). The exact equilibrium of the discrete
    chain (``analytic.discrete_catenary``) gives C = 0.49, 0.54, 0.93 for the sag at the
    three dL/L (C grows with the curvature of the cable). Tolerances: the error at each
    resolution must stay below 2 (h/L)^2 (at least twice the largest C; 7.8e-5 at N = 161)
    and the order fitted by ``numpy.polyfit(log h, log err)`` over the five resolutions must
    lie in [1.8, 2.2] (2 +- 10 %). The fit includes the coarsest mesh, 10 edges, where
    the h^4 term still shows: for H at dL/L = 0.5 the error falls only 2.2-fold from
    N = 11 to 21 (then 4-fold per halving), and the fit over all five gives 1.83; the band
    allows for that without admitting a first-order method (1.0). Two more rows per case at the
    finest resolution: catenet against the exact discrete chain (the solver's own error,
    tolerance 1e-9), and catenet against the inextensible Eq. 15 (information: the paper's
    cable is slightly extensible, W/EA = 1e-3: at N = 161 catenet's sag exceeds Eq. 15 by
    0.904 %, 0.126 % and 0.044 %, of which the exact elastic catenary accounts for 0.902 %,
    0.124 % and 0.040 %; the rest is the discretisation error).

(iii) Material laws. A bar of the paper's cable (EA = 3141.6 N, rest length L) fixed at one
    end and pulled along its axis at the other, for every law of ``catenet.model.laws.LAWS``
    (the table law with a three-segment table whose first slope is EA). The bar stays
    straight, so its strain solves EA w'(eps) = F exactly. At F = 1e-4 EA every law must
    give the paper's strain F/EA to 1e-3 relative (they differ at O(eps)), and at the force
    of 50 % strain under each law (neo-Hookean F/EA = (lambda - lambda^-2)/3, Hencky
    ln(lambda)/lambda, the table's interpolation) the strain must be 0.5 to 1e-9.

Every solve starts from catenet's default guess (the straight cable with its supports
moved). Should Newton fail from there, case (ii) retries from the previous resolution's
equilibrium interpolated onto the finer mesh and says so in the row's note.

``run()`` returns the rows; ``format_table`` and ``write_csv`` present them. Nothing here
prints: ``catenet.cli.validate`` does.
"""

from __future__ import annotations

import csv
import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from catenet.errors import ConfigError, ConvergenceError
from catenet.scene import Scene
from catenet.validate import analytic

if TYPE_CHECKING:
    from catenet.model.builders import Material

log = logging.getLogger(__name__)

# The paper's cable (Sec. 3.1).
LENGTH = 1.0  # m
YOUNG = 10e6  # Pa
RADIUS = 0.01  # m
DENSITY = 1000.0  # kg/m^3
GRAVITY = 9.81  # m/s^2

RTOL = 1e-10  # Newton's relative residual tolerance for every solve here
EXACT_TOL = 1e-9  # problems the discrete model solves exactly
MIDPOINT_NODES = (3, 21, 101, 401)
MIDPOINT_LOADS = (1e-4, 1e-3, 1e-2)  # F/EA; the load of 5 % strain is added
MIDPOINT_MAX_STRAIN = 0.05
CATENARY_DL = (0.05, 0.2, 0.5)  # dL/L
CATENARY_NODES = (11, 21, 41, 81, 161)
ORDER_BAND = (1.8, 2.2)
ERROR_CONSTANT = 2.0  # catenary tolerance: error <= ERROR_CONSTANT (h/L)^2

FIELDS = (
    "case",
    "quantity",
    "resolution",
    "catenet",
    "analytic",
    "rel_error",
    "order",
    "tolerance",
    "pass",
)


@dataclass(frozen=True)
class Row:
    """One comparison. ``resolution`` is the node count; ``order`` the observed order of
    the row's group (nan when not applicable); ``tolerance`` the bound on ``error`` (nan
    for rows that only inform); ``passed`` None for those rows."""

    case: str
    quantity: str
    resolution: int
    catenet: float
    analytic: float
    error: float
    order: float = math.nan
    tolerance: float = math.nan
    passed: bool | None = None
    note: str = ""

    def __post_init__(self) -> None:  # plain Python types (NumPy scalars print as np.float64(...))
        for name, value in (
            ("catenet", self.catenet),
            ("analytic", self.analytic),
            ("error", self.error),
            ("order", self.order),
            ("tolerance", self.tolerance),
        ):
            object.__setattr__(self, name, float(value))
        object.__setattr__(self, "resolution", int(self.resolution))
        if self.passed is not None:
            object.__setattr__(self, "passed", bool(self.passed))

    def failure(self) -> str:
        """Why the row failed ("" when it did not)."""
        if self.passed is not False:
            return ""
        why = []
        if not self.error <= self.tolerance:
            why.append(f"rel. error {self.error:.3g} > tol {self.tolerance:.3g}")
        if math.isfinite(self.order) and not ORDER_BAND[0] <= self.order <= ORDER_BAND[1]:
            why.append(f"order {self.order:.3f} outside [{ORDER_BAND[0]}, {ORDER_BAND[1]}]")
        if self.note:
            why.append(self.note)
        return "; ".join(why) or "failed"

    def as_dict(self) -> dict:
        return {
            "case": self.case,
            "quantity": self.quantity,
            "resolution": self.resolution,
            "catenet": self.catenet,
            "analytic": self.analytic,
            "rel_error": self.error,
            "order": self.order,
            "tolerance": self.tolerance,
            "pass": "" if self.passed is None else self.passed,
        }


def _material():
    from catenet.model.builders import Material

    return Material.from_E(YOUNG, radius=RADIUS, density=DENSITY)


def _rel(value: float, exact: float) -> float:
    if not math.isfinite(value):
        return math.inf
    return abs(value - exact) / abs(exact)


def observed_order(h: Sequence[float], err: Sequence[float]) -> float:
    """Slope of log(err) against log(h) by least squares (``numpy.polyfit``); nan when an
    error is zero or not finite."""
    hs = np.asarray(h, dtype=float)
    errs = np.asarray(err, dtype=float)
    if len(hs) < 2 or not np.all(np.isfinite(errs)) or not np.all(errs > 0):
        return math.nan
    return float(np.polyfit(np.log(hs), np.log(errs), 1)[0])


def midpoint_load_rows(
    nodes: Sequence[int] = MIDPOINT_NODES,
    loads: Sequence[float] = MIDPOINT_LOADS,
    max_strain: float = MIDPOINT_MAX_STRAIN,
) -> list[Row]:
    """Case (i): midpoint deflection delta/L against Eq. 17 (see the module docstring)."""
    from catenet.model.builders import cable
    from catenet.model.net import Loads

    material = _material()
    EA, L = material.EA, LENGTH
    # The load of max_strain: each half stretched to a (1 + eps), Eq. 17 at that delta.
    a = 0.5 * L
    delta_max = a * math.sqrt((1.0 + max_strain) ** 2 - 1.0)
    f_max = analytic.midpoint_load_force(delta_max, L, EA) / EA
    cases = [(f, f"midpoint F/EA={f:.0e}") for f in loads]
    cases.append((f_max, f"midpoint F/EA={f_max:.4f} ({100 * max_strain:g}% strain)"))
    rows = []
    for f_bar, name in cases:
        exact = analytic.midpoint_load_deflection(f_bar * EA, L, EA) / L
        for n in nodes:
            if n < 3 or n % 2 == 0:
                raise ConfigError(f"midpoint load: nodes = {n}: must be odd and >= 3")
            net = cable([-a, 0.0, 0.0], [a, 0.0, 0.0], n, material)
            force = np.zeros((n, 3))
            force[(n - 1) // 2, 2] = -f_bar * EA
            note = ""
            try:
                res = _solve(net, Loads(force=force))
                value = -res.x[(n - 1) // 2, 2] / L
            except ConvergenceError as exc:
                log.warning("%s, N = %d: %s", name, n, exc)
                value, note = math.nan, f"no convergence: {exc}"
            err = _rel(value, exact)
            rows.append(
                Row(
                    name,
                    "delta/L",
                    n,
                    value,
                    exact,
                    err,
                    tolerance=EXACT_TOL,
                    passed=err <= EXACT_TOL,
                    note=note,
                )
            )
    return rows


def _solve(net, loads, x0=None):
    """The static equilibrium through catenet's one solve path."""
    from catenet.solver import path as sv

    problem = Scene(net, loads)
    return sv.solve(problem, sv.Settings(rtol=RTOL), start=sv.Start(x=x0))


def _interpolate(x_coarse: np.ndarray, n: int) -> np.ndarray:
    """Positions of a coarse equilibrium at n evenly spaced material points."""
    s_old = np.linspace(0.0, 1.0, len(x_coarse))
    s = np.linspace(0.0, 1.0, n)
    return np.column_stack([np.interp(s, s_old, x_coarse[:, k]) for k in range(3)])


@dataclass(frozen=True)
class _Resolutions:
    """The compressed catenary at one dL/L, per node count (ascending): catenet's sag/L
    and H (nan where no solve converged) and each solve's note."""

    nodes: list[int]
    sags: list[float]
    Hs: list[float]
    notes: list[str]


def catenary_rows(
    dLs: Sequence[float] = CATENARY_DL, nodes: Sequence[int] = CATENARY_NODES
) -> list[Row]:
    """Case (ii): the compressed catenary against the exact elastic catenary, the exact
    discrete chain and Eq. 15 (see the module docstring)."""
    material = _material()
    EA, L = material.EA, LENGTH
    w = material.line_density * GRAVITY
    nodes = sorted(nodes)
    rows = []
    for dl in dLs:
        name = f"catenary dL/L={dl:g}"
        span = L - dl * L
        exact = analytic.elastic_catenary(L, EA, w, span)
        sag_ex, H_ex = exact.sag / L, exact.H
        runs = _catenary_runs(name, dl, nodes, material)
        rows += _elastic_rows(name, runs, sag_ex, H_ex)
        rows += _finest_rows(name, runs, dl, w, EA)
    return rows


def _catenary_runs(name: str, dl: float, nodes: list[int], material: Material) -> _Resolutions:
    """catenet's compressed catenary of dL/L = ``dl`` at every node count of ``nodes``."""
    from catenet.model.builders import cable
    from catenet.model.net import Loads

    L = LENGTH
    sags, Hs, notes = [], [], []
    x_prev = None
    for n in nodes:
        if n < 3 or n % 2 == 0:
            raise ConfigError(f"catenary: nodes = {n}: must be odd and >= 3")
        net = cable([-0.5 * L, 0.0, 0.0], [0.5 * L, 0.0, 0.0], n, material)
        move = np.zeros((n, 3))
        move[0, 0], move[-1, 0] = 0.5 * dl * L, -0.5 * dl * L
        loads = Loads(gravity=np.array([0.0, 0.0, -GRAVITY]), support_displacement=move)
        res, note = _catenary_solve(net, loads, x_prev, name, n)
        notes.append(note)
        if res is None:
            sags.append(math.nan)
            Hs.append(math.nan)
            x_prev = None
            continue
        x_prev = res.x
        sags.append(-res.x[(n - 1) // 2, 2] / L)
        Hs.append(0.5 * (res.reaction[-1, 0] - res.reaction[0, 0]))
    return _Resolutions(nodes, sags, Hs, notes)


def _catenary_solve(net, loads, x_prev, name: str, n: int):
    """The equilibrium from the straight cable, else from ``x_prev`` (the coarser
    equilibrium) interpolated onto the net, with the row's note; None if neither
    converges."""
    try:
        return _solve(net, loads), ""
    except ConvergenceError as exc:
        log.warning("%s, N = %d, from the straight cable: %s", name, n, exc)
        note = f"no convergence from the straight cable ({exc})"
    res = None
    if x_prev is not None:
        try:
            res = _solve(net, loads, _interpolate(x_prev, n))
            note += "; converged from the coarser equilibrium"
        except ConvergenceError as exc2:
            note += f"; nor from the coarser equilibrium ({exc2})"
    return res, note


def _elastic_rows(name: str, runs: _Resolutions, sag_ex: float, H_ex: float) -> list[Row]:
    """sag/L and H against the exact elastic catenary at every resolution, with the
    observed order of each quantity."""
    L = LENGTH
    rows = []
    h = [L / (n - 1) for n in runs.nodes]
    for quantity, values, ex in (("sag/L", runs.sags, sag_ex), ("H [N]", runs.Hs, H_ex)):
        errs = [_rel(v, ex) for v in values]
        order = observed_order(h, errs)
        order_ok = ORDER_BAND[0] <= order <= ORDER_BAND[1]
        for n, hh, v, e, note in zip(runs.nodes, h, values, errs, runs.notes, strict=True):
            tol = ERROR_CONSTANT * (hh / L) ** 2
            rows.append(
                Row(
                    name,
                    f"{quantity} elastic",
                    n,
                    v,
                    ex,
                    e,
                    order=order,
                    tolerance=tol,
                    passed=e <= tol and order_ok,
                    note=note,
                )
            )
    return rows


def _finest_rows(name: str, runs: _Resolutions, dl: float, w: float, EA: float) -> list[Row]:
    """The finest resolution's sag/L against the exact discrete chain and against Eq. 15."""
    L = LENGTH
    span = L - dl * L
    n, sag, note = runs.nodes[-1], runs.sags[-1], runs.notes[-1]
    chain = analytic.discrete_catenary(L, EA, w, span, n - 1).sag / L
    e = _rel(sag, chain)
    eq15 = analytic.catenary_sag(L, dl * L) / L
    return [
        Row(
            name,
            "sag/L chain",
            n,
            sag,
            chain,
            e,
            tolerance=EXACT_TOL,
            passed=e <= EXACT_TOL,
            note=note,
        ),
        Row(name, "sag/L Eq.15", n, sag, eq15, _rel(sag, eq15), note=note),
    ]


#: The table law of case (iii): (strain, tension / EA) points, first slope 1.
LAW_TABLE = ((0.1, 0.1), (0.3, 0.16), (0.8, 0.5))
SMALL_FORCE = 1e-4  # F/EA of the small-strain rows
SMALL_TOL = 1e-3  # every law is the paper's to O(eps)
LARGE_STRAIN = 0.5


def _law_force(name: str, eps: float) -> float:
    """N/EA of each law at strain eps, written out (independent of the kernels)."""
    lam = 1.0 + eps
    if name == "neo_hookean":
        return (lam - lam**-2) / 3.0
    if name == "hencky":
        return math.log(lam) / lam
    if name == "table":
        strain, force = zip(*((0.0, 0.0), *LAW_TABLE), strict=True)
        return float(np.interp(eps, strain, force))
    return eps


def law_rows() -> list[Row]:
    """Case (iii): every material law on a bar, at small strain and at 50 % strain."""
    from catenet.model.laws import LAWS, Law, table_rows
    from catenet.model.net import Loads, Net

    material = _material()
    EA, L = material.EA, LENGTH
    rows = []
    for name in LAWS:
        table = None
        if name == "table":
            table = table_rows([(e, f * EA) for e, f in LAW_TABLE])[0]
        law = Law.uniform(1, name, tension_only=False, table=table)
        net = Net.from_arrays([[0, 0, 0], [L, 0, 0]], [[0, 1]], EA=EA, fixed=[0], law=law)
        for f_bar, exact, tol, what in (
            (SMALL_FORCE, SMALL_FORCE, SMALL_TOL, "small strain, against the paper's law"),
            (_law_force(name, LARGE_STRAIN), LARGE_STRAIN, EXACT_TOL, "50 % strain"),
        ):
            force = np.zeros((2, 3))
            force[1, 0] = f_bar * EA
            note = ""
            try:
                strain = _solve(net, Loads(force=force)).x[1, 0] / L - 1.0
            except ConvergenceError as exc:
                strain, note = math.nan, f"no convergence: {exc}"
            err = _rel(strain, exact)
            rows.append(
                Row(
                    f"law {name}: {what}",
                    "strain",
                    2,
                    strain,
                    exact,
                    err,
                    tolerance=tol,
                    passed=err <= tol,
                    note=note,
                )
            )
    return rows


def run(progress: Callable[[str], None] | None = None) -> list[Row]:
    """Every row of the validation table: cases (i), (ii), (iii), the rods' (iv),
    ``catenet.validate.rods``, a published mooring system's (v),
    ``catenet.validate.moorings``, and the twisted rods' (vi), ``catenet.validate.twist``."""
    if progress:
        progress("midpoint load (Eqs. 16-17)")
    rows = midpoint_load_rows()
    if progress:
        progress("compressed catenary (Eqs. 14-15, elastic catenary)")
    rows += catenary_rows()
    if progress:
        progress("material laws (small strain, 50 % strain)")
    rows += law_rows()
    from catenet.validate.rods import rod_rows

    rows += [Row(**row) for row in rod_rows(progress)]
    if progress:
        progress("OC3-Hywind mooring lines: published restoring stiffness")
    from catenet.validate.moorings import oc3_rows

    rows += [Row(**row) for row in oc3_rows()]
    from catenet.validate.twist import twist_rows

    rows += [Row(**row) for row in twist_rows(progress)]
    return rows


def all_passed(rows: Sequence[Row]) -> bool:
    """True when no row with a tolerance failed it."""
    return all(r.passed is not False for r in rows)


def _fmt(value: float, spec: str) -> str:
    return "-" if not math.isfinite(value) else format(value, spec)


HEADER = ("case", "quantity", "N", "catenet", "analytic", "rel. error", "order", "tol", "ok")


def table_cells(rows: Sequence[Row]) -> list[tuple[str, ...]]:
    """The rows as the strings of the printed table (header first)."""
    cells: list[tuple[str, ...]] = [HEADER]
    for r in rows:
        ok = "info" if r.passed is None else ("yes" if r.passed else "NO")
        err = "inf" if math.isinf(r.error) else _fmt(r.error, ".2e")
        cells.append(
            (
                r.case,
                r.quantity,
                str(r.resolution),
                _fmt(r.catenet, ".12g"),
                _fmt(r.analytic, ".12g"),
                err,
                _fmt(r.order, ".3f"),
                _fmt(r.tolerance, ".1e"),
                ok,
            )
        )
    return cells


def format_table(rows: Sequence[Row]) -> str:
    """Aligned text table: text columns left-aligned, numbers right-aligned."""
    cells = table_cells(rows)
    widths = [max(len(c[i]) for c in cells) for i in range(len(HEADER))]
    left = {0, 1}
    lines = []
    for k, c in enumerate(cells):
        parts = [
            v.ljust(wd) if i in left else v.rjust(wd)
            for i, (v, wd) in enumerate(zip(c, widths, strict=True))
        ]
        lines.append("  ".join(parts).rstrip())
        if k == 0:
            lines.append("  ".join("-" * wd for wd in widths))
    return "\n".join(lines)


def write_csv(rows: Sequence[Row], path: str | Path) -> Path:
    """The rows as CSV (full precision, ``pass`` empty for information rows)."""
    path = Path(path)
    with path.open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=FIELDS)
        writer.writeheader()
        for r in rows:
            d = r.as_dict()
            writer.writerow({k: (repr(v) if isinstance(v, float) else v) for k, v in d.items()})
    return path
