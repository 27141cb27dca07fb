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
from collections.abc import Callable
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


Cell = Callable[[dict], str]


def num(key: str, digits: int = 3) -> Cell:
    """The column ``key`` as a number in short form."""
    return lambda r: g(r[key], digits)


def text(key: str) -> Cell:
    """The column ``key`` as it is."""
    return lambda r: r[key]


def table(rows: list[dict], columns: list[tuple[str, Cell]]) -> str:
    """The Markdown table of ``rows``: one column per (header, cell) pair."""
    return markdown([h for h, _ in columns], [[cell(r) for _, cell in columns] for r in rows])


def cpu_and_wall(rows: list[dict], cpu, wall, cpu_note: str) -> str:
    """A CPU time table (what a shared machine does not inflate), then wall time."""
    return (
        f"CPU time [s] ({cpu_note}):\n\n"
        + table(rows, cpu)
        + "\n\nWall time [s] on the shared machine (medians of the same runs):\n\n"
        + table(rows, wall)
    )


def _if_ok(cell: Cell) -> Cell:
    """An OpenSees row's cell where it found the equilibrium, else "-"."""
    return lambda r: cell(r) if r["opensees_ok"] == "0" else "-"


def _mib(a: str, b: str) -> Cell:
    return lambda r: f"{float(r[a]):.0f} / {float(r[b]):.0f}"


def opensees(rows: list[dict]) -> str:
    """CPU time (what a shared machine does not inflate), then wall time."""

    def engine(r: dict) -> str:
        return (
            g(r["opensees_engine_cpu_s"])
            + ("" if r["opensees_engine_warm"] == "True" else "*")
            + ("" if r["opensees_ok"] == "0" else " (no equilibrium)")
        )

    cpu = [
        ("DOF", text("dofs")),
        ("catenet solve", num("catenet_engine_cpu_s")),
        ("OpenSees analyze", engine),
        ("OpenSees / catenet", _if_ok(num("engine_cpu_ratio", 2))),
        ("`catenet run`", num("catenet_process_cpu_s")),
        ("OpenSees process", num("opensees_process_cpu_s")),
        ("OpenSees / catenet", _if_ok(num("process_cpu_ratio", 2))),
        (
            "Newton it. catenet / OpenSees",
            lambda r: f"{r['catenet_iterations']} / {r['opensees_iterations']}",
        ),
        ("peak MiB catenet / OpenSees", _mib("catenet_peak_mib", "opensees_peak_mib")),
        ("largest difference / delta", _if_ok(num("max_diff_over_delta", 2))),
    ]
    wall = [
        ("DOF", text("dofs")),
        ("catenet solve", num("catenet_engine_s")),
        ("OpenSees analyze", num("opensees_engine_s")),
        ("`catenet run`", num("catenet_process_s")),
        ("OpenSees process", num("opensees_process_s")),
        ("rounds", text("rounds")),
    ]
    note = "medians; * the analysis within the whole process, not warm"
    return cpu_and_wall(rows, cpu, wall, note)


def check(rows: list[dict]) -> str:
    return table(
        rows,
        [
            ("OpenSees system", text("system")),
            ("converged", lambda r: "yes" if r["ok"] == "0" else f"no ({r['ok']})"),
            ("Newton it.", text("iterations")),
            ("analyze [s]", num("analyze_s")),
            ("largest difference / delta, same law", num("diff_same_law", 2)),
            ("without the pretension", num("diff_no_pretension", 2)),
        ],
    )


def formfind(rows: list[dict]) -> str:
    """CPU time, then wall time."""
    cpu = [
        ("edges", text("edges")),
        ("catenet `formfind`", num("catenet_engine_cpu_s")),
        ("with `Net.from_arrays`", num("catenet_engine_with_net_cpu_s")),
        ("compas_fd `fd_numpy`", num("compas_engine_cpu_s")),
        ("catenet / compas_fd", num("engine_cpu_ratio", 2)),
        ("`catenet formfind` process", num("catenet_process_cpu_s")),
        ("compas_fd process", num("compas_process_cpu_s")),
        ("catenet / compas_fd", num("process_cpu_ratio", 2)),
        ("peak MiB catenet / compas_fd", _mib("catenet_peak_mib", "compas_peak_mib")),
        ("largest difference / span", num("max_dx_over_span", 2)),
    ]
    wall = [
        ("edges", text("edges")),
        ("catenet `formfind`", num("catenet_engine_s")),
        ("with `Net.from_arrays`", num("catenet_engine_with_net_s")),
        ("compas_fd `fd_numpy`", num("compas_engine_s")),
        ("catenet / compas_fd", num("engine_ratio", 2)),
        ("`catenet formfind` process", num("catenet_process_s")),
        ("compas_fd process", num("compas_process_s")),
        ("rounds", text("rounds")),
    ]
    return cpu_and_wall(rows, cpu, wall, "medians")


def pardiso(rows: list[dict]) -> str:
    def if_set(key: str) -> Cell:
        return lambda r: g(r[key], 2) if r[key] else ""

    return table(
        rows,
        [
            ("DOF", text("dofs")),
            ("binding", text("tool")),
            ("phase", text("phase")),
            ("CPU [s]", num("cpu_s")),
            ("wall [s]", num("seconds")),
            ("CPU x catenet's", if_set("over_catenet")),
            ("largest difference / largest x", if_set("max_dx_over_x")),
        ],
    )


def startup(rows: list[dict]) -> str:
    return table(
        rows,
        [
            ("fresh process", text("process")),
            ("CPU [s]", num("cpu_s")),
            ("CPU over the second [s]", num("cpu_over_floor_s")),
            ("wall [s]", num("seconds")),
        ],
    )


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
