"""The paper's square-net figures (Sec. 3.2, Figs. 5-8) and a report from a sweep directory.

``plot_sweep(directory, out)`` reads the sweep table (``results.jsonl``, or ``results.csv``)
and draws what its data allow:

- ``fig5_force_displacement_n.png``: delta/L against F_bar, one curve per n, panels
  alpha = 0 and alpha = pi/4;
- ``fig6_force_displacement_alpha.png``: one curve per alpha, panels n = 10 and n = 34;
- ``fig7_n_alpha.png``: delta/L against n (one curve per alpha) and against alpha (one
  curve per n, with the fitted cosine) at p = 10 Pa;
- ``fig8_scaling.png``: the collapse (delta/L)/f(alpha) against F_bar/n with the fitted
  master curve, and the log residuals about it;

and ``report.md``: the fitted scaling law with uncertainties, how well the collapse holds
and the paper's claims next to what catenet measures. A figure whose data the sweep lacks
is skipped with a note in the report, not an error.

The scaling law. The paper writes delta_bar / f(alpha) ~ F_bar / n with
f(alpha) = (D-1)/2 cos(4 alpha + pi) + (D+1)/2 (so f(0) = 1, f(pi/4) = D). "~" is read as
a power law, delta_bar = C f(alpha) (F_bar/n)^beta, and C, beta and D are fitted by
nonlinear least squares on log delta_bar (scipy.optimize.least_squares); their standard
errors come from the covariance s^2 (J^T J)^-1 at the optimum, s^2 the residual variance
with m - 3 degrees of freedom. A second fit frees the exponents of F_bar and n separately
(delta_bar = C f(alpha) F_bar^a n^b) to test whether they enter only as F_bar/n (a = -b).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from catenet.errors import ConfigError

log = logging.getLogger(__name__)

PAPER_D = 1.31
P_FIG7 = 10.0  # Pa, the paper's Fig. 7
ALPHA_TOL = 1e-6


def f_alpha(alpha, D):
    """The paper's orientation factor (Eq. 19): 1 at alpha = 0, D at alpha = pi/4."""
    return 0.5 * (D - 1.0) * np.cos(4.0 * np.asarray(alpha, dtype=float) + np.pi) + 0.5 * (D + 1.0)


@dataclass
class ScalingFit:
    """delta_bar = C f(alpha; D) x^beta, x = F_bar / n, fitted in log space."""

    C: float
    beta: float
    D: float
    sigma_C: float
    sigma_beta: float
    sigma_D: float
    rms_log: float  # RMS of log(delta_bar) residuals
    max_log: float  # largest |log residual|
    points: int
    fit_D: bool = True  # False when the data hold one orientation only (D fixed to 1)
    cov: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))
    residuals: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def predict(self, F_bar, n, alpha):
        x = np.asarray(F_bar, float) / np.asarray(n, float)
        return self.C * f_alpha(alpha, self.D) * x**self.beta


def fit_scaling(F_bar, n, alpha, delta_bar, *, D0: float = PAPER_D) -> ScalingFit:
    """Fit log delta_bar = log C + beta log(F_bar/n) + log f(alpha; D) by nonlinear least
    squares (Levenberg-Marquardt-style trust region on (log C, beta, D)); standard errors
    from the Jacobian at the optimum. Rows with delta_bar <= 0 or F_bar <= 0 are dropped."""
    from scipy.optimize import least_squares

    F_bar, n, alpha, delta_bar = (np.asarray(a, dtype=float) for a in (F_bar, n, alpha, delta_bar))
    ok = (delta_bar > 0) & (F_bar > 0) & (n > 0) & np.isfinite(delta_bar) & np.isfinite(alpha)
    F_bar, n, alpha, delta_bar = F_bar[ok], n[ok], alpha[ok], delta_bar[ok]
    lx = np.log(F_bar / n)
    ly = np.log(delta_bar)
    m = len(ly)
    if m < 3 or np.ptp(lx) <= 0:
        raise ConfigError(
            f"scaling fit: {m} usable points over {np.unique(lx).size} values of F_bar/n: "
            "need at least 3 points and 2 values of F_bar/n"
        )
    orient = np.cos(4.0 * alpha + np.pi)
    fit_D = np.ptp(orient) > 1e-9
    # A start from the linear fit with D = D0.
    beta0, logc0 = np.polyfit(lx, ly - np.log(f_alpha(alpha, D0 if fit_D else 1.0)), 1)

    if fit_D:

        def res(p):
            return p[0] + p[1] * lx + np.log(f_alpha(alpha, p[2])) - ly

        def jac(p):
            f = f_alpha(alpha, p[2])
            dfdD = 0.5 * orient + 0.5
            return np.column_stack([np.ones(m), lx, dfdD / f])

        sol = least_squares(
            res,
            [logc0, beta0, D0],
            jac=jac,
            bounds=([-np.inf, -np.inf, 1e-6], [np.inf, np.inf, np.inf]),
        )
        p = sol.x
        J = jac(p)
        dof = max(m - 3, 1)
    else:
        p = np.array([logc0, beta0, 1.0])
        J = np.column_stack([np.ones(m), lx])
        dof = max(m - 2, 1)
    r = p[0] + p[1] * lx + np.log(f_alpha(alpha, p[2])) - ly
    s2 = float(r @ r) / dof
    try:
        cov_small = s2 * np.linalg.inv(J.T @ J)
    except np.linalg.LinAlgError:
        cov_small = np.full((J.shape[1], J.shape[1]), np.nan)
    cov = np.zeros((3, 3))
    k = cov_small.shape[0]
    cov[:k, :k] = cov_small
    sig = np.sqrt(np.abs(np.diag(cov)))
    C = float(np.exp(p[0]))
    return ScalingFit(
        C=C,
        beta=float(p[1]),
        D=float(p[2]),
        sigma_C=C * float(sig[0]),
        sigma_beta=float(sig[1]),
        sigma_D=float(sig[2]),
        rms_log=float(np.sqrt(np.mean(r**2))),
        max_log=float(np.max(np.abs(r))),
        points=m,
        fit_D=bool(fit_D),
        cov=cov,
        residuals=r,
    )


def fit_exponents(F_bar, n, alpha, delta_bar, D: float) -> tuple[np.ndarray, np.ndarray]:
    """log delta_bar - log f(alpha; D) = log C + a log F_bar + b log n (linear least
    squares): (log C, a, b) and their standard errors. nan when n or F_bar takes a
    single value."""
    F_bar, n, alpha, delta_bar = (np.asarray(v, dtype=float) for v in (F_bar, n, alpha, delta_bar))
    ok = (delta_bar > 0) & (F_bar > 0) & (n > 0)
    y = np.log(delta_bar[ok]) - np.log(f_alpha(alpha[ok], D))
    A = np.column_stack([np.ones(ok.sum()), np.log(F_bar[ok]), np.log(n[ok])])
    if len(y) < 4 or np.ptp(A[:, 1]) <= 0 or np.ptp(A[:, 2]) <= 0:
        return np.full(3, np.nan), np.full(3, np.nan)
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    r = A @ coef - y
    s2 = float(r @ r) / max(len(y) - 3, 1)
    cov = s2 * np.linalg.inv(A.T @ A)
    return coef, np.sqrt(np.diag(cov))


def _linear_r2(x, y) -> tuple[float, float, float]:
    """Slope, intercept and R^2 of a straight-line fit."""
    b, a = np.polyfit(x, y, 1)
    pred = a + b * np.asarray(x)
    ss = float(np.sum((y - np.mean(y)) ** 2))
    r2 = 1.0 - float(np.sum((y - pred) ** 2)) / ss if ss > 0 else float("nan")
    return float(b), float(a), r2


def fit_cosine(alpha, delta_bar) -> tuple[float, float, float, float]:
    """delta_bar = a + b cos(4 alpha + pi) by linear least squares: (a, b, R^2, RMS of the
    relative residuals). The orientation factor it implies is D = (a + b) / (a - b)."""
    alpha = np.asarray(alpha, float)
    y = np.asarray(delta_bar, float)
    A = np.column_stack([np.ones_like(alpha), np.cos(4 * alpha + np.pi)])
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    pred = A @ coef
    ss = float(np.sum((y - y.mean()) ** 2))
    r2 = 1.0 - float(np.sum((y - pred) ** 2)) / ss if ss > 0 else float("nan")
    rel = float(np.sqrt(np.mean(((y - pred) / y) ** 2)))
    return float(coef[0]), float(coef[1]), r2, rel


# --------------------------------------------------------------------------------------------
# Data
# --------------------------------------------------------------------------------------------


@dataclass
class SweepData:
    """The successful rows of a square-net sweep, as arrays."""

    n: np.ndarray
    alpha: np.ndarray
    pressure: np.ndarray
    F_bar: np.ndarray
    delta_bar: np.ndarray
    rows: int
    failed: int
    keys: list[str]
    kind: str
    base: dict

    def select(self, mask) -> SweepData:
        return SweepData(
            self.n[mask],
            self.alpha[mask],
            self.pressure[mask],
            self.F_bar[mask],
            self.delta_bar[mask],
            int(np.count_nonzero(mask)),
            0,
            self.keys,
            self.kind,
            self.base,
        )


def _base_value(base: dict, key: str):
    cur = base
    for part in key.split("."):
        if not isinstance(cur, dict) or part not in cur:
            return None
        cur = cur[part]
    return cur


def load_data(directory: Path) -> SweepData:
    from catenet.sweep import read_journal, read_table

    keys, columns, table = read_table(directory)
    header, _ = read_journal(directory)
    base = (header or {}).get("base") or {}
    total = len(table.get("delta", []))

    def column(key: str, default=np.nan):
        if key in table:
            return np.array([_num(v) for v in table[key]], dtype=float)
        value = _base_value(base, key)
        value = default if value is None else _num(value)
        return np.full(total, value, dtype=float)

    error = table.get("error", [""] * total)
    conv = table.get("converged", [True] * total)
    ok = np.array([(not e) and bool(c) for e, c in zip(error, conv, strict=True)], dtype=bool)
    data = SweepData(
        n=column("geometry.n"),
        alpha=column("geometry.alpha"),
        pressure=column("load.pressure"),
        F_bar=column("F_bar"),
        delta_bar=column("delta_over_L"),
        rows=total,
        failed=int(np.count_nonzero(~ok)),
        keys=keys,
        kind=str(
            _base_value(base, "geometry.kind")
            or ("square_net" if "geometry.n" in keys else "unknown")
        ),
        base=base,
    )
    good = data.select(ok & np.isfinite(data.delta_bar))
    good.rows, good.failed = total, data.failed
    return good


def _num(v) -> float:
    if isinstance(v, bool):
        return float(v)
    if isinstance(v, int | float):
        return float(v)
    try:
        return float(v)
    except (TypeError, ValueError):
        return float("nan")


def _unique(values: np.ndarray) -> np.ndarray:
    values = np.sort(values[np.isfinite(values)])
    if values.size == 0:
        return values
    keep = np.concatenate([[True], np.diff(values) > ALPHA_TOL])
    return values[keep]


def _alpha_label(a: float) -> str:
    for num, den, text in (
        (1, 4, "π/4"),
        (1, 6, "π/6"),
        (1, 8, "π/8"),
        (1, 3, "π/3"),
        (1, 2, "π/2"),
    ):
        if abs(a - num * math.pi / den) < ALPHA_TOL:
            return f"α = {text}"
    return f"α = {a:.2f}"


def _near(values: np.ndarray, target: float, tol: float = ALPHA_TOL) -> np.ndarray:
    return np.abs(values - target) <= tol * max(1.0, abs(target))


# --------------------------------------------------------------------------------------------
# Figures
# --------------------------------------------------------------------------------------------


def _figure(ncols: int, width: float = 5.0, height: float = 4.0):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width * ncols, height), layout="constrained")
    FigureCanvasAgg(fig)
    axes = [fig.add_subplot(1, ncols, k + 1) for k in range(ncols)]
    return fig, axes


def _curves(ax, d: SweepData, group: np.ndarray, label) -> int:
    """delta_bar against F_bar, one curve per value of ``group``; the number drawn."""
    import matplotlib as mpl

    values = _unique(group)
    cmap = mpl.colormaps["viridis"]
    drawn = 0
    for k, g in enumerate(values):
        m = _near(group, g)
        if np.count_nonzero(m) < 2:
            continue
        order = np.argsort(d.F_bar[m])
        color = cmap(k / max(len(values) - 1, 1))
        ax.plot(d.F_bar[m][order], d.delta_bar[m][order], "o-", ms=3.5, color=color, label=label(g))
        drawn += 1
    ax.set_xlabel(r"$\bar F = pL^2/EA$")
    ax.set_ylabel(r"$\bar\delta = \delta/L$")
    ax.grid(alpha=0.3)
    if drawn:
        ax.legend(fontsize=8)
    return drawn


def _fig5(d: SweepData, path: Path, notes: list[str]) -> Path | None:
    panels = [a for a in (0.0, math.pi / 4) if np.any(_near(d.alpha, a))]
    if not panels or _unique(d.F_bar).size < 2:
        notes.append("Fig. 5 skipped: needs several load levels at α = 0 or α = π/4.")
        return None
    fig, axes = _figure(len(panels))
    for ax, a in zip(axes, panels, strict=True):
        sub = d.select(_near(d.alpha, a))
        _curves(ax, sub, sub.n, lambda g: f"n = {int(round(g))}")
        ax.set_title(f"Fig. 5: {_alpha_label(a)}")
    missing = [lbl for a, lbl in ((0.0, "α = 0"), (math.pi / 4, "α = π/4")) if a not in panels]
    if missing:
        notes.append(f"Fig. 5: panel {', '.join(missing)} skipped (not in the sweep).")
    fig.savefig(path, dpi=130)
    return path


def _fig6(d: SweepData, path: Path, notes: list[str]) -> Path | None:
    ns = _unique(d.n)
    if ns.size == 0 or _unique(d.F_bar).size < 2:
        notes.append("Fig. 6 skipped: needs several load levels.")
        return None
    panels = [v for v in (10.0, 34.0) if np.any(_near(d.n, v))]
    if not panels:
        panels = sorted({float(ns[0]), float(ns[-1])})
        notes.append(
            f"Fig. 6: n = 10 and n = 34 are not in the sweep; drawn for n = "
            f"{', '.join(str(int(v)) for v in panels)}."
        )
    fig, axes = _figure(len(panels))
    for ax, nv in zip(axes, panels, strict=True):
        sub = d.select(_near(d.n, nv))
        _curves(ax, sub, sub.alpha, _alpha_label)
        ax.set_title(f"Fig. 6: n = {int(nv)}")
    fig.savefig(path, dpi=130)
    return path


def _fig7_subset(d: SweepData, notes: list[str]) -> tuple[SweepData | None, float]:
    ps = _unique(d.pressure)
    if ps.size == 0:
        notes.append("Fig. 7 skipped: the table has no load.pressure.")
        return None, float("nan")
    p = float(ps[np.argmin(np.abs(ps - P_FIG7))])
    if abs(p - P_FIG7) > 1e-9:
        notes.append(f"Fig. 7: the sweep has no p = {P_FIG7:g} Pa; drawn at p = {p:g} Pa.")
    return d.select(_near(d.pressure, p)), p


def _fig7(d: SweepData, path: Path, notes: list[str]) -> Path | None:
    sub, p = _fig7_subset(d, notes)
    if sub is None:
        return None
    ns, alphas = _unique(sub.n), _unique(sub.alpha)
    if ns.size < 2 and alphas.size < 2:
        notes.append("Fig. 7 skipped: needs several n or several α.")
        return None
    import matplotlib as mpl

    fig, axes = _figure(2)
    cmap = mpl.colormaps["viridis"]
    ax = axes[0]
    if ns.size >= 2:
        for k, a in enumerate(alphas):
            m = _near(sub.alpha, a)
            order = np.argsort(sub.n[m])
            ax.plot(
                sub.n[m][order],
                sub.delta_bar[m][order],
                "o-",
                ms=4,
                color=cmap(k / max(len(alphas) - 1, 1)),
                label=_alpha_label(a),
            )
        ax.legend(fontsize=8)
    else:
        notes.append("Fig. 7a skipped: one value of n.")
    ax.set_xlabel("number of cables n")
    ax.set_ylabel(r"$\bar\delta = \delta/L$")
    ax.set_title(f"Fig. 7a: p = {p:g} Pa")
    ax.grid(alpha=0.3)
    ax = axes[1]
    if alphas.size >= 2:
        grid = np.linspace(0.0, math.pi / 4, 100)
        for k, nv in enumerate(ns):
            m = _near(sub.n, nv)
            order = np.argsort(sub.alpha[m])
            color = cmap(k / max(len(ns) - 1, 1))
            ax.plot(
                sub.alpha[m][order],
                sub.delta_bar[m][order],
                "o",
                ms=5,
                color=color,
                label=f"n = {int(nv)}",
            )
            if np.count_nonzero(m) >= 3:
                a0, b0, _, _ = fit_cosine(sub.alpha[m], sub.delta_bar[m])
                ax.plot(grid, a0 + b0 * np.cos(4 * grid + np.pi), "-", lw=1, color=color)
        ax.legend(fontsize=8, title="lines: a + b cos(4α+π)", title_fontsize=8)
    else:
        notes.append("Fig. 7b skipped: one value of α.")
    ax.set_xlabel(r"fibre orientation $\alpha$ [rad]")
    ax.set_ylabel(r"$\bar\delta = \delta/L$")
    ax.set_title(f"Fig. 7b: p = {p:g} Pa")
    ax.grid(alpha=0.3)
    fig.savefig(path, dpi=130)
    return path


def _fig8(d: SweepData, fit: ScalingFit | None, path: Path, notes: list[str]) -> Path | None:
    if fit is None:
        notes.append("Fig. 8 skipped: the scaling law could not be fitted (see above).")
        return None
    import matplotlib as mpl

    fig, axes = _figure(2)
    x = d.F_bar / d.n
    y = d.delta_bar / f_alpha(d.alpha, fit.D)
    ns, alphas = _unique(d.n), _unique(d.alpha)
    markers = "os^Dv<>ph*"
    cmap = mpl.colormaps["viridis"]
    resid = np.log(y) - np.log(fit.C * x**fit.beta)
    for i, nv in enumerate(ns):
        for j, a in enumerate(alphas):
            m = _near(d.n, nv) & _near(d.alpha, a)
            if not m.any():
                continue
            kw = dict(
                color=cmap(i / max(len(ns) - 1, 1)),
                marker=markers[j % len(markers)],
                ls="none",
                ms=4,
                mfc="none",
            )
            label = f"n = {int(nv)}" if j == 0 else None
            axes[0].loglog(x[m], y[m], label=label, **kw)
            axes[1].semilogx(x[m], resid[m], **kw)
    xs = np.geomspace(x.min(), x.max(), 50)
    axes[0].loglog(
        xs, fit.C * xs**fit.beta, "k-", lw=1, label=rf"$C(\bar F/n)^{{\beta}}$, β = {fit.beta:.3f}"
    )
    for j, a in enumerate(alphas):
        axes[0].plot(
            [],
            [],
            color="gray",
            marker=markers[j % len(markers)],
            ls="none",
            mfc="none",
            label=_alpha_label(a),
        )
    axes[0].set_xlabel(r"$\bar F/n$")
    axes[0].set_ylabel(r"$\bar\delta/f(\alpha)$")
    axes[0].set_title(f"Fig. 8: D = {fit.D:.3f} ± {fit.sigma_D:.3f} (paper: {PAPER_D})")
    axes[0].legend(fontsize=7, ncol=2)
    axes[0].grid(alpha=0.3, which="both")
    axes[1].axhline(0.0, color="k", lw=0.8)
    axes[1].set_xlabel(r"$\bar F/n$")
    axes[1].set_ylabel("log residual about the master curve")
    axes[1].set_title(f"RMS {fit.rms_log:.3f} (≈ {100 * math.expm1(fit.rms_log):.1f} %)")
    axes[1].grid(alpha=0.3)
    fig.savefig(path, dpi=130)
    return path


# --------------------------------------------------------------------------------------------
# The report
# --------------------------------------------------------------------------------------------


def _fmt(v: float, digits: int = 4) -> str:
    return "n/a" if v is None or not np.isfinite(v) else f"{v:.{digits}g}"


def _claims(d: SweepData, fit: ScalingFit | None, notes: list[str]) -> list[str]:
    lines = ["| Paper | catenet measures | Verdict |", "|---|---|---|"]
    sub, p = _fig7_subset(d, [])
    # 1. Rigidity linear in n (Fig. 7a: delta decreases almost linearly with n).
    ns = _unique(sub.n) if sub is not None else np.array([])
    if sub is not None and ns.size >= 3:
        r2s, gammas = [], []
        for a in _unique(sub.alpha):
            m = _near(sub.alpha, a)
            if np.count_nonzero(m) >= 3:
                _, _, r2 = _linear_r2(sub.n[m], sub.delta_bar[m])
                g, _ = np.polyfit(np.log(sub.n[m]), np.log(sub.delta_bar[m]), 1)
                r2s.append(r2)
                gammas.append(g)
        k_exp = -float(np.mean(gammas))
        line_fit = (
            "a straight line fits δ̄(n) well"
            if min(r2s) > 0.98
            else f"a straight line fits δ̄(n) only roughly (R² ≥ {min(r2s):.2f})"
        )
        if abs(k_exp - 1) > 0.2:
            verdict = (
                f"Partly: δ̄ decreases with n and {line_fit}, but the trend is a power law "
                f"δ̄ ∝ n^γ: the rigidity F̄/δ̄ grows like n^{k_exp:.2f}, not like n."
            )
        else:
            verdict = f"Agrees: the rigidity grows about linearly with n (n^{k_exp:.2f})."
        lines.append(
            f"| δ̄ decreases almost linearly with n (Fig. 7a, p = 10 Pa); rigidity grows "
            f"linearly with n | straight-line fits of δ̄(n) at p = {p:g} Pa: R² = "
            f"{min(r2s):.3f}–{max(r2s):.3f}; power law δ̄ ∝ n^γ with γ = "
            f"{min(gammas):.3f} to {max(gammas):.3f} (one value per α) | {verdict} |"
        )
    else:
        notes.append("Claim 'rigidity linear in n' not checked: needs ≥ 3 values of n.")
    # 2. Cosine dependence on alpha.
    alphas = _unique(sub.alpha) if sub is not None else np.array([])
    if sub is not None and alphas.size >= 3:
        r2s, rels, Ds = [], [], []
        for nv in _unique(sub.n):
            m = _near(sub.n, nv)
            if np.count_nonzero(m) >= 3:
                a0, b0, r2, rel = fit_cosine(sub.alpha[m], sub.delta_bar[m])
                r2s.append(r2)
                rels.append(rel)
                Ds.append((a0 + b0) / (a0 - b0))
        good = min(r2s) > 0.95
        lines.append(
            f"| δ̄ follows a cosine in α (Fig. 7b) | δ̄ = a + b cos(4α+π) at p = {p:g} Pa, per n: "
            f"R² = {min(r2s):.3f}–{max(r2s):.3f}, RMS relative residual "
            f"{100 * min(rels):.2f}–{100 * max(rels):.2f} %; δ̄(π/4)/δ̄(0) of the fit = "
            f"{min(Ds):.3f}–{max(Ds):.3f} | "
            f"{'Agrees' if good else 'Does not agree well'}: the α-dependence "
            f"{'is' if good else 'is not'} well described by cos(4α+π) |"
        )
    else:
        notes.append("Claim 'cosine dependence on α' not checked: needs ≥ 3 values of α.")
    # 3. D and 4. the form of the law.
    if fit is not None and fit.fit_D:
        z = (fit.D - PAPER_D) / fit.sigma_D if fit.sigma_D > 0 else float("inf")
        close = abs(fit.D - PAPER_D) <= 0.05 * PAPER_D
        lines.append(
            f"| D ≈ {PAPER_D} (Eq. 19) | D = {fit.D:.4f} ± {fit.sigma_D:.4f} (1σ), "
            f"{abs(z):.0f}σ from {PAPER_D} | "
            f"{'Agrees within 5 %' if close else 'Does not agree'}: catenet's nets are "
            f"{100 * (fit.D - 1):.0f} % softer at α = π/4 than at α = 0, the paper's "
            f"{100 * (PAPER_D - 1):.0f} % |"
        )
    if fit is not None:
        spread = 100 * math.expm1(fit.rms_log)
        lines.append(
            f"| δ̄/f(α) ~ F̄/n collapses all data (Eq. 18, Fig. 8) | δ̄/f(α) = C (F̄/n)^β with "
            f"β = {fit.beta:.4f} ± {fit.sigma_beta:.4f}, C = {fit.C:.4g}; RMS log residual "
            f"{fit.rms_log:.4f} (≈ {spread:.1f} %), largest {fit.max_log:.3f} over "
            f"{fit.points} points | "
            + (
                "Agrees: the data collapse onto one power law in F̄/n"
                if fit.rms_log < 0.05
                else "Partly: the collapse has visible scatter"
            )
            + (
                f"; the exponent is {fit.beta:.2f}, so δ̄ is not proportional to F̄/n "
                "(a net without pretension stiffens as it deflects)"
                if abs(fit.beta - 1) > 0.1
                else ""
            )
            + " |"
        )
    return lines


def write_report(
    directory: Path,
    d: SweepData,
    fit: ScalingFit | None,
    general,
    figures: list[Path],
    notes: list[str],
    path: Path,
) -> Path:
    lines = ["# Square-net sweep: the paper's scaling law checked", ""]
    lines.append(
        f"Sweep `{directory}`: {d.rows} rows, {d.failed} failed or not converged "
        f"(left out); {d.n.size} used. Swept: {', '.join(d.keys) or 'nothing'}."
    )
    lines.append("")
    lines.append("## Scaling law")
    lines.append("")
    if fit is None:
        lines.append("Not fitted (see the notes).")
    else:
        lines += [
            "Model: δ̄ = C f(α; D) (F̄/n)^β with f(α) = (D−1)/2 cos(4α+π) + (D+1)/2, fitted by "
            "nonlinear least squares on log δ̄ (standard errors from s²(JᵀJ)⁻¹ at the optimum).",
            "",
            "| Quantity | Value | 1σ |",
            "|---|---|---|",
            f"| D | {fit.D:.4f} | {fit.sigma_D:.4f} |"
            if fit.fit_D
            else "| D | not identifiable (one orientation class) | |",
            f"| β | {fit.beta:.4f} | {fit.sigma_beta:.4f} |",
            f"| C | {fit.C:.5g} | {fit.sigma_C:.2g} |",
            f"| RMS of log residuals | {fit.rms_log:.4f} "
            f"(≈ {100 * math.expm1(fit.rms_log):.2f} %) | |",
            f"| largest abs. log residual | {fit.max_log:.4f} | |",
            f"| points | {fit.points} | |",
            "",
        ]
        coef, err = general
        if np.all(np.isfinite(coef)):
            lines += [
                "Exponents of F̄ and n fitted separately, δ̄ = C f(α; D) F̄^a n^b (D as above): "
                f"a = {coef[1]:.4f} ± {err[1]:.4f}, b = {coef[2]:.4f} ± {err[2]:.4f}. "
                "The law in F̄/n alone needs a = −b: "
                f"a + b = {coef[1] + coef[2]:.4f}.",
                "",
            ]
    lines.append("## The paper's claims and what catenet measures")
    lines.append("")
    lines += _claims(d, fit, notes)
    lines.append("")
    lines.append("## Figures")
    lines.append("")
    for f in figures:
        lines.append(f"- `{f.name}`")
    if notes:
        lines.append("")
        lines.append("## Notes")
        lines.append("")
        lines += [f"- {n}" for n in notes]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def plot_sweep(directory: Path, out: Path | None = None) -> list[Path]:
    """Figures 5-8 of the paper from the sweep in ``directory`` and ``report.md``, written
    to ``out`` (default: the sweep directory). Returns the paths written."""
    directory = Path(directory)
    out = Path(out) if out is not None else directory
    out.mkdir(parents=True, exist_ok=True)
    d = load_data(directory)
    notes: list[str] = []
    written: list[Path] = []
    if d.kind != "square_net":
        notes.append(
            f"geometry.kind = {d.kind!r}: the paper's figures are for square nets; none drawn."
        )
        return [
            write_report(
                directory, d, None, (np.full(3, np.nan),) * 2, [], notes, out / "report.md"
            )
        ]
    if d.n.size == 0:
        notes.append("No successful rows: nothing to plot.")
        return [
            write_report(
                directory, d, None, (np.full(3, np.nan),) * 2, [], notes, out / "report.md"
            )
        ]
    fit = None
    general = (np.full(3, np.nan), np.full(3, np.nan))
    try:
        fit = fit_scaling(d.F_bar, d.n, d.alpha, d.delta_bar)
        general = fit_exponents(d.F_bar, d.n, d.alpha, d.delta_bar, fit.D)
        if not fit.fit_D:
            notes.append(
                "D not fitted: the sweep holds one orientation class (cos 4α takes "
                "one value); f(α) = 1 was used."
            )
    except ConfigError as exc:
        notes.append(f"Scaling law not fitted: {'; '.join(exc.problems)}")
    for maker, name in (
        (_fig5, "fig5_force_displacement_n.png"),
        (_fig6, "fig6_force_displacement_alpha.png"),
        (_fig7, "fig7_n_alpha.png"),
    ):
        p = maker(d, out / name, notes)
        if p is not None:
            written.append(p)
    p = _fig8(d, fit, out / "fig8_scaling.png", notes)
    if p is not None:
        written.append(p)
    report = write_report(directory, d, fit, general, written, notes, out / "report.md")
    log.info("wrote %s", ", ".join(str(p) for p in written + [report]))
    return written + [report]
