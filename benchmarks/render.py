"""Fills the tables of docs/performance.md from the studies' CSV files.

The page is written by hand. Each part of it that comes from a study's table (a Markdown
table, or a sentence whose numbers it holds) sits between ``<!-- results:NAME -->`` and
``<!-- /results:NAME -->``; ``render(results_dir, page)`` replaces what is between them
with ``FRAGMENTS[NAME](results_dir)`` and copies the figures ``bench-*.png`` to
``figures/`` beside the page. A fragment whose study has not run (no CSV) is left as it
is; its name is returned.

    python -m benchmarks render [-o benchmarks/results] [--docs docs/performance.md]
"""

from __future__ import annotations

import json
import logging
import re
import shutil
from pathlib import Path

from benchmarks import drop, integrators, sections, sections_peers, sections_reuse, sections_scale
from benchmarks.sections import as_float, as_text, read_study

log = logging.getLogger(__name__)

MARKER = re.compile(
    r"(<!-- results:(?P<name>[a-z0-9-]+) -->\n)(?P<body>.*?)(<!-- /results:(?P=name) -->)", re.S
)


def machine(results: Path) -> list[str]:
    path = results / "machine.json"
    if not path.exists():
        return []
    m = json.loads(path.read_text())
    return [
        f"Measured on: **{m.get('cpu', '?')}**, {m.get('cores', '?')} cores, "
        f"{m.get('memory_gib', '?')} GiB, {m.get('system', '')}; Python {m.get('python', '')}, "
        f"NumPy {m.get('numpy', '')}, SciPy {m.get('scipy', '')}, Numba {m.get('numba', '')}, "
        f"pypardiso {m.get('pypardiso', '')} (MKL {m.get('mkl', '')})."
    ]


def _summary(results: Path) -> list[str]:
    """The headline numbers, each from its study's table."""
    out: list[str] = []
    base = read_study(results, "baseline") or []
    cat = next((r for r in base if r["n"] == "34" and r["method"] == "catenet (pardiso)"), None)
    bl = next(
        (r for r in base if r["n"] == "34" and r["method"] == "baseline numpy+pypardiso"), None
    )
    prop = next(
        (
            r
            for r in base
            if r["n"] == "34" and "proposed" in r["method"] and "pardiso" in r["method"]
        ),
        None,
    )
    if cat:
        line = (
            f"- **Static equilibrium of the paper's n = 34 net ({cat['dofs']} DOF): "
            f"{as_text(cat['seconds'])} s** warm, one thread"
        )
        if bl:
            line += (
                f", {as_text(bl['ratio_to_catenet'], '{:.1f}')}x faster than a plain NumPy/"
                "pypardiso implementation of the same method"
            )
        if prop:
            line += (
                f" ({as_text(prop['seconds'])} s and "
                f"{as_text(as_float(bl['seconds']) / as_float(prop['seconds']), '{:.1f}')}x "
                "with the two PARDISO settings below)"
                if bl
                else ""
            )
        out.append(line + ".")
    steps = read_study(results, "step-size") or []
    dyn = [r for r in steps if r["n"] == "34" and r["equilibrium"] == "True"]
    if dyn:
        fast = min(dyn, key=lambda r: as_float(r["wall_seconds"]))
        slow = max(dyn, key=lambda r: as_float(r["wall_seconds"]))
        out.append(
            f"- The paper's own method, dynamic relaxation of the same net: "
            f"{as_text(fast['wall_seconds'])} s (h = {as_text(fast['h'], '{:g}')} s) to "
            f"{as_text(slow['wall_seconds'])} s (h = {as_text(slow['h'], '{:g}')} s) to "
            "equilibrium, against the paper's < 20 s."
        )
    scale = [
        r
        for r in (read_study(results, "scale") or [])
        if r.get("dofs") and r.get("variant", "default") == "default"
    ]
    if scale:
        top = scale[-1]
        out.append(
            f"- {top['dofs']} DOF: {as_text(top['total_seconds'])} s, peak "
            f"{as_text(as_float(top['peak_rss_mib']) / 1024, '{:.2f}')} GiB."
        )
    cold = read_study(results, "cold-start") or []
    warm = next(
        (r for r in cold if r["numba_cache"] == "warm" and r["threads"] == "as installed"), None
    )
    first = next(
        (
            r
            for r in cold
            if r["numba_cache"].startswith("empty") and r["threads"] == "as installed"
        ),
        None,
    )
    helps = next((r for r in cold if r["command"] == "catenet --help"), None)
    if warm and first:
        out.append(
            f"- `{warm['command'].split(' (')[0]}` on the default case: "
            f"{as_text(first['seconds'])} s the first time (JIT compilation), "
            f"{as_text(warm['seconds'])} s after; `catenet --help` {as_text(helps['seconds'])} s."
            if helps
            else ""
        )
    stress = read_study(results, "stress") or []
    if stress:
        ok = sum(r["passed"] == "True" for r in stress)
        out.append(f"- Stress test: {ok} of {len(stress)} hard scenes give a right answer.")
    skips = read_study(results, "skips") or []
    slower = []
    for what in dict.fromkeys(r["skip"] for r in skips):
        sel = [
            r
            for r in skips
            if r["skip"] == what and as_float(r["seconds"]) == as_float(r["seconds"])
        ]
        default = next((r for r in sel if r["default"] == "True"), None)
        alt = [r for r in sel if r["default"] != "True"]
        if default and alt:
            best = min(alt, key=lambda r: as_float(r["seconds"]))
            if as_float(best["ratio_to_default"]) < 0.8:
                slower.append(
                    f"{what}: {best['variant']} takes "
                    f"{as_text(best['ratio_to_default'], '{:.2f}')}x the default's time"
                )
    if slower:
        out += [
            "- Defaults that are not the faster choice (measured below; differences under "
            "about 20 % are within the noise of a shared machine): " + "; ".join(slower) + "."
        ]
    return out


FRAGMENTS = {
    "machine": machine,
    "summary": _summary,
    "static": sections.static,
    "step-size": sections.step_size,
    "scale": sections_scale.scale,
    "pareto": sections.pareto,
    "skips": sections.skips,
    "cold-start": sections.cold_start,
    "revisions": sections.revisions,
    "formfind": sections.formfind,
    "flush": sections.flush,
    "reuse": sections_reuse.reuse,
    "stress": sections.stress,
    "integrators": integrators.section,
    "drop": drop.section,
    "peers-mujoco": sections_peers.mujoco,
}


def fragment(name: str, results: Path) -> list[str]:
    """The lines of one fragment; [] when its study has not run or wrote another format."""
    try:
        return FRAGMENTS[name](Path(results))
    except (KeyError, ValueError, IndexError) as exc:  # a CSV of another version
        log.warning("render: %s skipped: %r", name, exc)
        return []


def render(results_dir: Path, page: Path) -> list[str]:
    """Fills ``page``'s fragments from ``results_dir``; the names of those left as they
    were (no results). Raises ValueError for a marker of an unknown fragment."""
    results, page = Path(results_dir), Path(page)
    text = page.read_text()
    unknown = sorted({m["name"] for m in MARKER.finditer(text)} - set(FRAGMENTS))
    if unknown:
        raise ValueError(f"{page}: unknown fragments {unknown}: one of {sorted(FRAGMENTS)}")
    missing: list[str] = []

    def fill(m: re.Match) -> str:
        lines = fragment(m["name"], results)
        if not lines:
            missing.append(m["name"])
            return m[0]
        return m[1] + "\n".join(lines).strip("\n") + "\n" + m[4]

    page.write_text(MARKER.sub(fill, text))
    figures = page.parent / "figures"
    figures.mkdir(parents=True, exist_ok=True)
    for png in sorted(results.glob("bench-*.png")):
        shutil.copy2(png, figures / png.name)
    return missing
