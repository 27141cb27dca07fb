"""``plot_sweep``: the figures and ``report.md`` of a square-net sweep, with the paper's
claims next to what catenet measures and a verdict on each."""

from __future__ import annotations

import logging
import math
from pathlib import Path

import numpy as np

from catenet.errors import ConfigError
from catenet.study.data import SweepData, load_data, near, unique
from catenet.study.figures import fig5, fig6, fig7, fig7_subset, fig8
from catenet.study.fit import (
    PAPER_D,
    ScalingFit,
    fit_cosine,
    fit_exponents,
    fit_scaling,
    linear_r2,
)

log = logging.getLogger(__name__)


def _claims(d: SweepData, fit: ScalingFit | None, notes: list[str]) -> list[str]:
    """The Markdown table of the paper's claims, what catenet measures and a verdict on
    each; a claim the sweep cannot check gets a line in ``notes`` instead."""
    lines = ["| Paper | catenet measures | Verdict |", "|---|---|---|"]
    sub, p = fig7_subset(d, [])
    for row in (
        _linear_in_n(sub, p, notes),
        _cosine_in_alpha(sub, p, notes),
        _paper_D(fit),
        _collapse(fit),
    ):
        if row is not None:
            lines.append(row)
    return lines


def _linear_in_n(sub: SweepData | None, p: float, notes: list[str]) -> str | None:
    """Claim 1, the rigidity linear in n (Fig. 7a: delta decreases almost linearly with
    n): its row, None (and a note) without 3 values of n."""
    ns = unique(sub.n) if sub is not None else np.array([])
    if sub is None or ns.size < 3:
        notes.append("Claim 'rigidity linear in n' not checked: needs ≥ 3 values of n.")
        return None
    r2s, gammas = [], []
    for a in unique(sub.alpha):
        m = near(sub.alpha, a)
        if np.count_nonzero(m) >= 3:
            _, _, r2 = linear_r2(sub.n[m], sub.delta_bar[m])
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
    return (
        f"| δ̄ decreases almost linearly with n (Fig. 7a, p = 10 Pa); rigidity grows "
        f"linearly with n | straight-line fits of δ̄(n) at p = {p:g} Pa: R² = "
        f"{min(r2s):.3f}–{max(r2s):.3f}; power law δ̄ ∝ n^γ with γ = "
        f"{min(gammas):.3f} to {max(gammas):.3f} (one value per α) | {verdict} |"
    )


def _cosine_in_alpha(sub: SweepData | None, p: float, notes: list[str]) -> str | None:
    """Claim 2, delta a cosine in alpha (Fig. 7b): its row, None (and a note) without 3
    values of alpha."""
    alphas = unique(sub.alpha) if sub is not None else np.array([])
    if sub is None or alphas.size < 3:
        notes.append("Claim 'cosine dependence on α' not checked: needs ≥ 3 values of α.")
        return None
    r2s, rels, Ds = [], [], []
    for nv in unique(sub.n):
        m = near(sub.n, nv)
        if np.count_nonzero(m) >= 3:
            a0, b0, r2, rel = fit_cosine(sub.alpha[m], sub.delta_bar[m])
            r2s.append(r2)
            rels.append(rel)
            Ds.append((a0 + b0) / (a0 - b0))
    good = min(r2s) > 0.95
    return (
        f"| δ̄ follows a cosine in α (Fig. 7b) | δ̄ = a + b cos(4α+π) at p = {p:g} Pa, per n: "
        f"R² = {min(r2s):.3f}–{max(r2s):.3f}, RMS relative residual "
        f"{100 * min(rels):.2f}–{100 * max(rels):.2f} %; δ̄(π/4)/δ̄(0) of the fit = "
        f"{min(Ds):.3f}–{max(Ds):.3f} | "
        f"{'Agrees' if good else 'Does not agree well'}: the α-dependence "
        f"{'is' if good else 'is not'} well described by cos(4α+π) |"
    )


def _paper_D(fit: ScalingFit | None) -> str | None:
    """Claim 3, D close to the paper's (Eq. 19): its row, None when D was not fitted."""
    if fit is None or not fit.fit_D:
        return None
    z = (fit.D - PAPER_D) / fit.sigma_D if fit.sigma_D > 0 else float("inf")
    close = abs(fit.D - PAPER_D) <= 0.05 * PAPER_D
    return (
        f"| D ≈ {PAPER_D} (Eq. 19) | D = {fit.D:.4f} ± {fit.sigma_D:.4f} (1σ), "
        f"{abs(z):.0f}σ from {PAPER_D} | "
        f"{'Agrees within 5 %' if close else 'Does not agree'}: catenet's nets are "
        f"{100 * (fit.D - 1):.0f} % softer at α = π/4 than at α = 0, the paper's "
        f"{100 * (PAPER_D - 1):.0f} % |"
    )


def _collapse(fit: ScalingFit | None) -> str | None:
    """Claim 4, the form of the law: every point on one curve in F/n (Eq. 18, Fig. 8);
    its row, None without a fit."""
    if fit is None:
        return None
    spread = 100 * math.expm1(fit.rms_log)
    return (
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
        (fig5, "fig5_force_displacement_n.png"),
        (fig6, "fig6_force_displacement_alpha.png"),
        (fig7, "fig7_n_alpha.png"),
    ):
        p = maker(d, out / name, notes)
        if p is not None:
            written.append(p)
    p = fig8(d, fit, out / "fig8_scaling.png", notes)
    if p is not None:
        written.append(p)
    report = write_report(directory, d, fit, general, written, notes, out / "report.md")
    log.info("wrote %s", ", ".join(str(p) for p in written + [report]))
    return written + [report]
