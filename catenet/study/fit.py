"""The paper's scaling law fitted to a square-net sweep: delta_bar = C f(alpha; D)
(F_bar/n)^beta by nonlinear least squares on log delta_bar, the exponents of F_bar and n
fitted separately, and the cosine in alpha of Fig. 7b."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from catenet.errors import ConfigError

PAPER_D = 1.31


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


def linear_r2(x, y) -> tuple[float, float, float]:
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
