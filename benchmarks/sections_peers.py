"""Fragments of docs/performance.md from the peers' tables (``benchmarks/peers/``)."""

from __future__ import annotations

from pathlib import Path

from benchmarks.sections import as_text, md_table, read_study


def mujoco(results: Path) -> list[str]:
    """catenet against MuJoCo (``benchmarks/peers/mujoco_capture.py``): one row per scene
    and tool; [] when the study has not run."""
    rows = read_study(results, "peers-mujoco")
    if not rows:
        return []
    version = next((r["version"] for r in rows if r["tool"].startswith("MuJoCo")), "")
    header = [
        "scene",
        "tool",
        "box momentum at the end [kg m/s]",
        "off catenet's",
        "deepest penetration [m]",
        "largest stable step [s]",
        "largest accurate step [s]",
        "penetration there [m]",
        "steps",
        "engine CPU [s]",
        "whole process CPU [s]",
    ]
    body = []
    for r in rows:
        body.append(
            [
                r["scene"],
                r["tool"],
                r["momentum"],
                as_text(r.get("momentum_vs_catenet"), "{:.1%}"),
                as_text(r.get("penetration_reference"), "{:.2g}"),
                as_text(r.get("stable_dt"), "{:.3g}"),
                as_text(r.get("accurate_dt"), "{:.3g}"),
                as_text(r.get("penetration_at_accurate_dt"), "{:.2g}"),
                r.get("steps", ""),
                as_text(r.get("engine_cpu_seconds")),
                as_text(r.get("process_cpu_seconds")),
            ]
        )
    out = [f"MuJoCo {version}, catenet's implicit Euler:", "", *md_table(header, body)]
    check = read_study(results, "peers-mujoco-integrators") or []
    if check:
        out += ["", "catenet's two integrators on the same scenes, the box at the end:", ""]
        out += md_table(
            ["scene", "integrator", "dt [s]", "box momentum [kg m/s]", "largest momentum [kg m/s]"],
            [
                [r["scene"], r["integrator"], as_text(r["dt"], "{:g}"), r["momentum"],
                 as_text(r["peak_momentum"])]
                for r in check
            ],
        )  # fmt: skip
    return out
