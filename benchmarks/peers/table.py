"""Markdown tables of the peer comparisons, from benchmarks/results/peers-*.csv.

    python benchmarks/peers/table.py [--results benchmarks/results] [--readme README.md]

Prints one table per CSV that exists: OpenSees (engine and whole process), its check,
compas_fd (form finding) and pypardiso (phases and start-up). With ``--readme`` it fills
them into that Markdown file instead, between each ``<!-- peers-NAME.csv -->`` line and
the next ``<!-- end -->``.
"""

from __future__ import annotations

import argparse
import csv
import re
from pathlib import Path

RESULTS = Path(__file__).resolve().parent.parent / "results"


def g(value, digits: int = 3) -> str:
    """A number in a short form; text as it is."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        return str(value)
    if v == 0.0:
        return "0"
    if abs(v) < 1e-3 or abs(v) >= 1e5:
        return f"{v:.1e}"
    return f"{v:.{digits}g}"


def markdown(header: list[str], rows: list[list]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += [
        "| " + " | ".join(g(c) if not isinstance(c, str) else c for c in r) + " |" for r in rows
    ]
    return "\n".join(lines)


def read(path: Path) -> list[dict]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def opensees(rows: list[dict]) -> str:
    """CPU time (what a shared machine does not inflate), then wall time."""
    cpu = [
        "DOF",
        "catenet solve",
        "OpenSees analyze",
        "OpenSees / catenet",
        "`catenet run`",
        "OpenSees process",
        "OpenSees / catenet",
        "Newton it. catenet / OpenSees",
        "peak MiB catenet / OpenSees",
        "largest difference / delta",
    ]
    body = [
        [
            r["dofs"],
            g(r["catenet_engine_cpu_s"]),
            g(r["opensees_engine_cpu_s"])
            + ("" if r["opensees_engine_warm"] == "True" else "*")
            + ("" if r["opensees_ok"] == "0" else " (no equilibrium)"),
            g(r["engine_cpu_ratio"], 2) if r["opensees_ok"] == "0" else "-",
            g(r["catenet_process_cpu_s"]),
            g(r["opensees_process_cpu_s"]),
            g(r["process_cpu_ratio"], 2) if r["opensees_ok"] == "0" else "-",
            f"{r['catenet_iterations']} / {r['opensees_iterations']}",
            f"{float(r['catenet_peak_mib']):.0f} / {float(r['opensees_peak_mib']):.0f}",
            g(r["max_diff_over_delta"], 2) if r["opensees_ok"] == "0" else "-",
        ]
        for r in rows
    ]
    wall = [
        "DOF",
        "catenet solve",
        "OpenSees analyze",
        "`catenet run`",
        "OpenSees process",
        "rounds",
    ]
    body2 = [
        [
            r["dofs"],
            g(r["catenet_engine_s"]),
            g(r["opensees_engine_s"]),
            g(r["catenet_process_s"]),
            g(r["opensees_process_s"]),
            r["rounds"],
        ]
        for r in rows
    ]
    return (
        "CPU time [s] (medians; * the analysis within the whole process, not warm):\n\n"
        + markdown(cpu, body)
        + "\n\nWall time [s] on the shared machine (medians of the same runs):\n\n"
        + markdown(wall, body2)
    )


def check(rows: list[dict]) -> str:
    header = [
        "OpenSees system",
        "converged",
        "Newton it.",
        "analyze [s]",
        "largest difference / delta, same law",
        "without the pretension",
    ]
    body = [
        [
            r["system"],
            "yes" if r["ok"] == "0" else f"no ({r['ok']})",
            r["iterations"],
            g(r["analyze_s"]),
            g(r["diff_same_law"], 2),
            g(r["diff_no_pretension"], 2),
        ]
        for r in rows
    ]
    return markdown(header, body)


def formfind(rows: list[dict]) -> str:
    """CPU time, then wall time."""
    cpu = [
        "edges",
        "catenet `formfind`",
        "with `Net.from_arrays`",
        "compas_fd `fd_numpy`",
        "catenet / compas_fd",
        "`catenet formfind` process",
        "compas_fd process",
        "catenet / compas_fd",
        "peak MiB catenet / compas_fd",
        "largest difference / span",
    ]
    body = [
        [
            r["edges"],
            g(r["catenet_engine_cpu_s"]),
            g(r["catenet_engine_with_net_cpu_s"]),
            g(r["compas_engine_cpu_s"]),
            g(r["engine_cpu_ratio"], 2),
            g(r["catenet_process_cpu_s"]),
            g(r["compas_process_cpu_s"]),
            g(r["process_cpu_ratio"], 2),
            f"{float(r['catenet_peak_mib']):.0f} / {float(r['compas_peak_mib']):.0f}",
            g(r["max_dx_over_span"], 2),
        ]
        for r in rows
    ]
    wall = [
        "edges",
        "catenet `formfind`",
        "with `Net.from_arrays`",
        "compas_fd `fd_numpy`",
        "catenet / compas_fd",
        "`catenet formfind` process",
        "compas_fd process",
        "rounds",
    ]
    body2 = [
        [
            r["edges"],
            g(r["catenet_engine_s"]),
            g(r["catenet_engine_with_net_s"]),
            g(r["compas_engine_s"]),
            g(r["engine_ratio"], 2),
            g(r["catenet_process_s"]),
            g(r["compas_process_s"]),
            r["rounds"],
        ]
        for r in rows
    ]
    return (
        "CPU time [s] (medians):\n\n"
        + markdown(cpu, body)
        + "\n\nWall time [s] on the shared machine (medians of the same runs):\n\n"
        + markdown(wall, body2)
    )


def pardiso(rows: list[dict]) -> str:
    header = [
        "DOF",
        "binding",
        "phase",
        "CPU [s]",
        "wall [s]",
        "CPU x catenet's",
        "largest difference / largest x",
    ]
    body = [
        [
            r["dofs"],
            r["tool"],
            r["phase"],
            g(r["cpu_s"]),
            g(r["seconds"]),
            g(r["over_catenet"], 2) if r["over_catenet"] else "",
            g(r["max_dx_over_x"], 2) if r["max_dx_over_x"] else "",
        ]
        for r in rows
    ]
    return markdown(header, body)


def startup(rows: list[dict]) -> str:
    header = ["fresh process", "CPU [s]", "CPU over the second [s]", "wall [s]"]
    body = [[r["process"], g(r["cpu_s"]), g(r["cpu_over_floor_s"]), g(r["seconds"])] for r in rows]
    return markdown(header, body)


TABLES = (
    ("peers-opensees-check.csv", "OpenSees: the check (n = 34, 10047 DOF)", check),
    ("peers-opensees.csv", "OpenSees: engine and whole process", opensees),
    ("peers-formfind.csv", "compas_fd: form finding", formfind),
    ("peers-pardiso.csv", "pypardiso: PARDISO's phases", pardiso),
    ("peers-pardiso-startup.csv", "pypardiso: start-up", startup),
)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--results", type=Path, default=RESULTS)
    p.add_argument("--readme", type=Path, help="fill the tables into this file")
    a = p.parse_args()
    if a.readme:
        text = a.readme.read_text()
        for name, _, render in TABLES:
            path = a.results / name
            if path.exists():
                table = render(read(path))
                text = re.sub(
                    rf"(<!-- {re.escape(name)} -->\n).*?(\n<!-- end -->)",
                    lambda m, t=table: m.group(1) + t + m.group(2),
                    text,
                    flags=re.S,
                )
        a.readme.write_text(text)
        return
    for name, title, render in TABLES:
        path = a.results / name
        if path.exists():
            print(f"#### {title}\n\n<!-- {name} -->\n{render(read(path))}\n")


if __name__ == "__main__":
    main()
