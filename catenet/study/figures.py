"""The paper's Figs. 5-8 from a square-net sweep; each returns the path written, or None
with a note when the sweep lacks its data."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from catenet.study.data import SweepData, alpha_label, near, unique
from catenet.study.fit import PAPER_D, ScalingFit, f_alpha, fit_cosine

P_FIG7 = 10.0  # Pa, the paper's Fig. 7

#: Okabe-Ito colours without their yellow: told apart by colour-blind readers and in print.
COLOURS = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000")
MARKERS = "os^Dv<>ph*"
LINES = ("-", "--", "-.", ":")


def style(k: int) -> dict:
    """Colour, marker and line style of the k-th curve of a figure: each differs from
    its neighbours' in all three, so curves stay apart even in grey print."""
    return {
        "color": COLOURS[k % len(COLOURS)],
        "marker": MARKERS[k % len(MARKERS)],
        "ls": LINES[k % len(LINES)],
    }


def _figure(ncols: int, width: float = 5.0, height: float = 4.0):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width * ncols, height), layout="constrained")
    FigureCanvasAgg(fig)
    axes = [fig.add_subplot(1, ncols, k + 1) for k in range(ncols)]
    return fig, axes


def _curves(ax, d: SweepData, group: np.ndarray, label) -> int:
    """delta_bar against F_bar, one curve per value of ``group``; the number drawn."""
    values = unique(group)
    drawn = 0
    for k, g in enumerate(values):
        m = near(group, g)
        if np.count_nonzero(m) < 2:
            continue
        order = np.argsort(d.F_bar[m])
        ax.plot(d.F_bar[m][order], d.delta_bar[m][order], ms=3.5, label=label(g), **style(k))
        drawn += 1
    ax.set_xlabel(r"$\bar F = pL^2/EA$")
    ax.set_ylabel(r"$\bar\delta = \delta/L$")
    ax.grid(alpha=0.3)
    if drawn:
        ax.legend(fontsize=8)
    return drawn


def fig5(d: SweepData, path: Path, notes: list[str]) -> Path | None:
    panels = [a for a in (0.0, math.pi / 4) if np.any(near(d.alpha, a))]
    if not panels or unique(d.F_bar).size < 2:
        notes.append("Fig. 5 skipped: needs several load levels at α = 0 or α = π/4.")
        return None
    fig, axes = _figure(len(panels))
    for ax, a in zip(axes, panels, strict=True):
        sub = d.select(near(d.alpha, a))
        _curves(ax, sub, sub.n, lambda g: f"n = {int(round(g))}")
        ax.set_title(f"Fig. 5: {alpha_label(a)}")
    missing = [lbl for a, lbl in ((0.0, "α = 0"), (math.pi / 4, "α = π/4")) if a not in panels]
    if missing:
        notes.append(f"Fig. 5: panel {', '.join(missing)} skipped (not in the sweep).")
    fig.savefig(path, dpi=130)
    return path


def fig6(d: SweepData, path: Path, notes: list[str]) -> Path | None:
    ns = unique(d.n)
    if ns.size == 0 or unique(d.F_bar).size < 2:
        notes.append("Fig. 6 skipped: needs several load levels.")
        return None
    panels = [v for v in (10.0, 34.0) if np.any(near(d.n, v))]
    if not panels:
        panels = sorted({float(ns[0]), float(ns[-1])})
        notes.append(
            f"Fig. 6: n = 10 and n = 34 are not in the sweep; drawn for n = "
            f"{', '.join(str(int(v)) for v in panels)}."
        )
    fig, axes = _figure(len(panels))
    for ax, nv in zip(axes, panels, strict=True):
        sub = d.select(near(d.n, nv))
        _curves(ax, sub, sub.alpha, alpha_label)
        ax.set_title(f"Fig. 6: n = {int(nv)}")
    fig.savefig(path, dpi=130)
    return path


def fig7_subset(d: SweepData, notes: list[str]) -> tuple[SweepData | None, float]:
    ps = unique(d.pressure)
    if ps.size == 0:
        notes.append("Fig. 7 skipped: the table has no load.pressure.")
        return None, float("nan")
    p = float(ps[np.argmin(np.abs(ps - P_FIG7))])
    if abs(p - P_FIG7) > 1e-9:
        notes.append(f"Fig. 7: the sweep has no p = {P_FIG7:g} Pa; drawn at p = {p:g} Pa.")
    return d.select(near(d.pressure, p)), p


def fig7(d: SweepData, path: Path, notes: list[str]) -> Path | None:
    sub, p = fig7_subset(d, notes)
    if sub is None:
        return None
    ns, alphas = unique(sub.n), unique(sub.alpha)
    if ns.size < 2 and alphas.size < 2:
        notes.append("Fig. 7 skipped: needs several n or several α.")
        return None
    fig, axes = _figure(2)
    ax = axes[0]
    if ns.size >= 2:
        for k, a in enumerate(alphas):
            m = near(sub.alpha, a)
            order = np.argsort(sub.n[m])
            ax.plot(
                sub.n[m][order], sub.delta_bar[m][order], ms=4, label=alpha_label(a), **style(k)
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
            m = near(sub.n, nv)
            order = np.argsort(sub.alpha[m])
            st = style(k)
            ax.plot(
                sub.alpha[m][order],
                sub.delta_bar[m][order],
                ls="none",
                marker=st["marker"],
                ms=5,
                color=st["color"],
                label=f"n = {int(nv)}",
            )
            if np.count_nonzero(m) >= 3:
                a0, b0, _, _ = fit_cosine(sub.alpha[m], sub.delta_bar[m])
                curve = a0 + b0 * np.cos(4 * grid + np.pi)
                ax.plot(grid, curve, ls=st["ls"], lw=1, color=st["color"])
        ax.legend(fontsize=8, title="lines: a + b cos(4α+π)", title_fontsize=8)
    else:
        notes.append("Fig. 7b skipped: one value of α.")
    ax.set_xlabel(r"fibre orientation $\alpha$ [rad]")
    ax.set_ylabel(r"$\bar\delta = \delta/L$")
    ax.set_title(f"Fig. 7b: p = {p:g} Pa")
    ax.grid(alpha=0.3)
    fig.savefig(path, dpi=130)
    return path


def fig8(d: SweepData, fit: ScalingFit | None, path: Path, notes: list[str]) -> Path | None:
    if fit is None:
        notes.append("Fig. 8 skipped: the scaling law could not be fitted (see above).")
        return None
    fig, axes = _figure(2)
    x = d.F_bar / d.n
    y = d.delta_bar / f_alpha(d.alpha, fit.D)
    ns, alphas = unique(d.n), unique(d.alpha)
    markers = MARKERS
    resid = np.log(y) - np.log(fit.C * x**fit.beta)
    for i, nv in enumerate(ns):
        for j, a in enumerate(alphas):
            m = near(d.n, nv) & near(d.alpha, a)
            if not m.any():
                continue
            kw = dict(
                color=COLOURS[i % len(COLOURS)],
                marker=markers[j % len(markers)],
                ls="none",
                ms=4,
                mfc="none",
            )
            label = f"n = {int(nv)}" if j == 0 else None
            axes[0].loglog(x[m], y[m], label=label, **kw)
            axes[1].semilogx(x[m], resid[m], label=label, **kw)
    xs = np.geomspace(x.min(), x.max(), 50)
    axes[0].loglog(
        xs, fit.C * xs**fit.beta, "k-", lw=1, label=rf"$C(\bar F/n)^{{\beta}}$, β = {fit.beta:.3f}"
    )
    for ax in axes:  # the marker of each alpha, once per panel
        for j, a in enumerate(alphas):
            ax.plot(
                [],
                [],
                color="gray",
                marker=markers[j % len(markers)],
                ls="none",
                mfc="none",
                label=alpha_label(a),
            )
    axes[0].set_xlabel(r"$\bar F/n$")
    axes[0].set_ylabel(r"$\bar\delta/f(\alpha)$")
    axes[0].set_title(f"Fig. 8: D = {fit.D:.3f} ± {fit.sigma_D:.3f} (paper: {PAPER_D})")
    axes[0].legend(fontsize=7, ncol=2)
    axes[0].grid(alpha=0.3, which="both")
    axes[1].axhline(0.0, color="k", lw=0.8, label="master curve")
    axes[1].set_xlabel(r"$\bar F/n$")
    axes[1].set_ylabel(r"residual $\ln(\bar\delta/f) - \ln(C(\bar F/n)^{\beta})$ (natural log)")
    axes[1].legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    axes[1].set_title(f"RMS {fit.rms_log:.3f} (≈ {100 * math.expm1(fit.rms_log):.1f} %)")
    axes[1].grid(alpha=0.3)
    fig.savefig(path, dpi=130)
    return path
