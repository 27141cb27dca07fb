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

Modules: ``fit`` (the scaling law), ``data`` (the sweep table as arrays), ``figures``
(Figs. 5-8), ``report`` (``report.md`` and ``plot_sweep``).
"""

from __future__ import annotations

from catenet.study.data import SweepData, load_data
from catenet.study.fit import (
    PAPER_D,
    ScalingFit,
    f_alpha,
    fit_cosine,
    fit_exponents,
    fit_scaling,
)
from catenet.study.report import plot_sweep, write_report

__all__ = [
    "PAPER_D",
    "ScalingFit",
    "SweepData",
    "f_alpha",
    "fit_cosine",
    "fit_exponents",
    "fit_scaling",
    "load_data",
    "plot_sweep",
    "write_report",
]
