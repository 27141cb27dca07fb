"""Numerical damping of the time integrators against the step size, and what it does to
the paper's damping study (App. A, Fig. A.9).

Three parts, one CSV (``kind`` column):

- ``analysis``: the damping ratio and relative period error each scheme adds to an
  undamped mode at h omega (``catenet.solver.spectral.numerical_damping``, from the
  eigenvalues of the scheme's amplification matrix): implicit Euler, newmark with
  rho_inf = 1 (average acceleration), the default and 0.5;
- ``measured``: the same ratio measured on the solver: a pretensioned string (10
  segments, EA = 1e4 N, 1 % strain, mu = 0) started with the velocity of its lowest
  mode (omega = 99.4 1/s), run for PERIODS periods (or until the energy of the motion,
  kinetic + strain above the straight string's, has fallen below FLOOR times its start);
  xi = -ln(E / E_0) / (2 omega t) at the end;
- ``settling``: configs/damping_mu{0.1,1,10}.toml (n = 10, h = 0.01 s, lowest period
  about 0.15 s) with implicit Euler and with newmark at rho_inf = 0.9 as in
  configs/dynamics/damping_newmark_mu*.toml: the simulated time to rest (dynamic relaxation's
  test: static residual and inertial force below rtol), steps and wall time. Where
  physics damps, the settling time is about 2 ln(1/rtol) / mu.
"""

from __future__ import annotations

import sys
from pathlib import Path

if __package__ in (None, ""):  # python benchmarks/integrators.py: the repository root on the path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import logging
import math
import time

from benchmarks.common import (
    Study,
    no_progress,
    paper_net,
    pyplot,
    save_figure,
    set_threads,
    tabulate,
    warm_up,
)

log = logging.getLogger(__name__)

NAME = "integrators"
TITLE = "Numerical damping of the time integrators"

SCHEMES = (("implicit_euler", 1.0), ("newmark", 1.0), ("newmark", None), ("newmark", 0.5))
H_OMEGA = (0.05, 0.1, 0.2, 0.5, 1.0, 2.0)
PERIODS = 10
FLOOR = 1e-8  # the decay is measured while E / E_0 is above this
OMEGA = 99.4  # 1/s, the string's lowest mode (2 sqrt(T / (m l)) sin(pi / 20))
MUS = ("0.1", "1", "10")
CONFIG_RHO = 0.9  # configs/dynamics/damping_newmark_mu*.toml


def label(name: str, rho_inf: float) -> str:
    return "implicit Euler" if name == "implicit_euler" else f"newmark rho_inf={rho_inf:g}"


def string_motion(name: str, rho_inf: float, h_omega: float) -> float:
    """The measured damping ratio of the string's lowest mode at step h omega."""
    import numpy as np

    from catenet.model.net import Loads, Net
    from catenet.solver.dynamic import solve_dynamic
    from catenet.solver.static import Workspace

    n = 11
    s = np.linspace(0.0, 1.0, n)
    nodes = np.c_[s, 0 * s, 0 * s]
    edges = np.c_[np.arange(n - 1), np.arange(1, n)]
    net = Net.from_arrays(
        nodes, edges, EA=1e4, fixed=[0, n - 1], rest_length=0.099, line_density=0.1
    )
    v0 = np.zeros_like(nodes)
    v0[:, 2] = 0.3 * np.sin(np.pi * s)
    ws = Workspace(net)
    rest = ws.system.gradient(net.nodes)[0]
    mass = net.mass[:, None]

    def motion(x, v) -> float:
        return 0.5 * float(np.sum(mass * v * v)) + ws.system.gradient(x)[0] - rest

    e0 = motion(net.nodes, v0)
    seen = [(0.0, 1.0)]  # (t, E / E_0) while E is above the solver's resolution

    def step(k, t, x, v):
        ratio = motion(x, v) / e0
        if ratio < FLOOR:
            return True
        seen.append((t, ratio))
        return False

    t_end = PERIODS * 2 * math.pi / OMEGA
    solve_dynamic(
        net,
        Loads(),
        dt=h_omega / OMEGA,
        damping=0.0,
        t_end=t_end,
        rtol=1e-12,
        v0=v0,
        stop_at_equilibrium=False,
        integrator=name,
        rho_inf=rho_inf,
        workspace=ws,
        on_step=step,
    )
    t, ratio = seen[-1]
    return -math.log(ratio) / (2.0 * OMEGA * t)


def settling(mu: str, name: str) -> dict:
    """The paper's n = 10 net (configs/damping_mu<mu>.toml) relaxed with ``name``."""
    from catenet.solver.dynamic import solve_dynamic

    sq, loads = paper_net(10)
    start = time.perf_counter()
    r = solve_dynamic(
        sq.net,
        loads,
        dt=0.01,
        damping=float(mu),
        t_end=800.0,  # physics alone: about 370 s at mu = 0.1 (see the docstring)
        integrator=name,
        rho_inf=CONFIG_RHO,
    )
    return {
        "settle_seconds": r.time,
        "steps": r.steps,
        "at_rest": bool(r.equilibrium),
        "wall_seconds": time.perf_counter() - start,
    }


def run(out_dir: Path, *, quick: bool = False, progress=no_progress, threads: int = 1) -> Study:
    from catenet.solver.integrators import RHO_INF
    from catenet.solver.spectral import numerical_damping

    set_threads(threads)
    warm_up()
    schemes = [(n, RHO_INF if r is None else r) for n, r in SCHEMES]
    rows = []
    for name, rho in schemes:
        for k in range(41):
            s = 10 ** (-2 + 4 * k / 40)
            xi, period = numerical_damping(name, s, rho)
            rows.append(
                {
                    "kind": "analysis",
                    "scheme": label(name, rho),
                    "h_omega": s,
                    "xi": xi,
                    "period_error": period,
                }
            )
    h_omegas = (0.1, 0.5, 2.0) if quick else H_OMEGA
    mus = ("1", "10") if quick else MUS
    total = len(schemes) * len(h_omegas) + 2 * len(mus)
    done = 0
    for name, rho in schemes:
        for s in h_omegas:
            progress(done, total, f"{label(name, rho)}, h omega = {s:g}")
            rows.append(
                {
                    "kind": "measured",
                    "scheme": label(name, rho),
                    "h_omega": s,
                    "xi": string_motion(name, rho, s),
                    "xi_analysis": numerical_damping(name, s, rho)[0],
                }
            )
            done += 1
    for name in ("implicit_euler", "newmark"):
        for mu in mus:
            progress(done, total, f"damping_mu{mu}, {name}")
            row = {"kind": "settling", "scheme": label(name, CONFIG_RHO), "mu": float(mu)}
            row.update(settling(mu, name))
            rows.append(row)
            done += 1
    progress(total, total, "")
    return tabulate(Study(NAME, rows, Path(out_dir) / f"{NAME}.csv"), out_dir, figure, _line)


def _line(r: dict) -> str | None:
    if r["kind"] == "measured":
        return (
            f"{r['scheme']:<22} h omega = {r['h_omega']:<5g} xi = {r['xi']:.2e} "
            f"(analysis {r['xi_analysis']:.2e})"
        )
    if r["kind"] == "settling":
        return (
            f"{r['scheme']:<22} mu = {r['mu']:<4g} "
            + ("at rest after" if r["at_rest"] else "NOT at rest by")
            + f" {r['settle_seconds']:.4g} s "
            f"({r['steps']} steps, {r['wall_seconds']:.3g} s wall)"
        )
    return None  # the analysis' rows: in the table and the figure only


def figure(rows, out_dir):
    plt = pyplot()
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    for k, scheme in enumerate(dict.fromkeys(r["scheme"] for r in rows)):
        color = f"C{k}"
        sel = [r for r in rows if r["scheme"] == scheme and r["kind"] == "analysis"]
        ax1.loglog(
            [r["h_omega"] for r in sel],
            [max(r["xi"], 1e-9) for r in sel],
            "-",
            color=color,
            label=scheme,
        )
        got = [r for r in rows if r["scheme"] == scheme and r["kind"] == "measured"]
        ax1.loglog([r["h_omega"] for r in got], [max(r["xi"], 1e-9) for r in got], "o", color=color)
    ax1.set_xlabel("h omega")
    ax1.set_ylabel("numerical damping ratio xi")
    ax1.set_ylim(1e-7, 10)
    ax1.set_title("lines: analysis, dots: the string's lowest mode")
    ax1.legend(fontsize=8)
    for k, scheme in enumerate(dict.fromkeys(r["scheme"] for r in rows)):
        sel = [r for r in rows if r["scheme"] == scheme and r["kind"] == "settling"]
        if sel:
            ax2.loglog(
                [r["mu"] for r in sel], [r["settle_seconds"] for r in sel], "o-", color=f"C{k}",
                label=scheme,
            )  # fmt: skip
            for r in sel:
                if str(r["at_rest"]) != "True":  # stopped at t_end, not at rest
                    ax2.plot(r["mu"], r["settle_seconds"], "x", color="k", ms=10)
    mus = [0.1, 10.0]
    ax2.loglog(mus, [2 * math.log(1e8) / m for m in mus], "k:", label="2 ln(1/rtol) / mu")
    ax2.set_xlabel("mu [1/s]")
    ax2.set_ylabel("simulated time to rest [s]")
    ax2.set_title("configs/damping_mu*.toml, h = 0.01 s (x: not at rest by t_end)")
    ax2.legend(fontsize=8)
    fig.tight_layout()
    return save_figure(fig, out_dir, NAME)


def section(results: Path) -> list[str]:
    """docs/performance.md's tables of this study (``python -m benchmarks render``)."""
    from benchmarks.sections import as_text, md_table, read_study

    rows = read_study(results, NAME)
    if not rows:
        return []
    out: list[str] = []
    measured = [r for r in rows if r["kind"] == "measured"]
    schemes = list(dict.fromkeys(r["scheme"] for r in measured))
    h_omegas = list(dict.fromkeys(r["h_omega"] for r in measured))
    table = []
    for s in h_omegas:
        line = [as_text(s, "{:g}")]
        for scheme in schemes:
            r = next(q for q in measured if q["scheme"] == scheme and q["h_omega"] == s)
            line.append(f"{as_text(r['xi'], '{:.1e}')} ({as_text(r['xi_analysis'], '{:.1e}')})")
        table.append(line)
    out += md_table(["h omega", *schemes], table)
    settle = [r for r in rows if r["kind"] == "settling"]
    if settle:
        out += ["", *md_table(
            ["integrator", "mu [1/s]", "time to rest [s]", "steps", "wall [s]"],
            [[r["scheme"], as_text(r["mu"], "{:g}"), as_text(r["settle_seconds"], "{:.4g}")
              + ("" if str(r["at_rest"]) == "True" else " (not at rest)"),
              r["steps"], as_text(r["wall_seconds"])] for r in settle],
        )]  # fmt: skip
    return out


if __name__ == "__main__":
    from benchmarks.__main__ import script

    script(NAME)
