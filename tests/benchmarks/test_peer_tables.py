"""The Markdown tables of the peer comparisons (benchmarks/peers/table.py)."""

from __future__ import annotations

from benchmarks.peers import table


def _opensees_row(ok: str, warm: str) -> dict:
    keys = (
        "dofs catenet_engine_cpu_s opensees_engine_cpu_s engine_cpu_ratio catenet_process_cpu_s "
        "opensees_process_cpu_s process_cpu_ratio catenet_iterations opensees_iterations "
        "catenet_peak_mib opensees_peak_mib max_diff_over_delta catenet_engine_s "
        "opensees_engine_s catenet_process_s opensees_process_s rounds"
    ).split()
    row = {key: "0.5" for key in keys}
    row.update(dofs="975", opensees_ok=ok, opensees_engine_warm=warm, rounds="7")
    return row


def test_opensees_tables_mark_cold_analyses_and_rows_without_equilibrium():
    text = table.opensees([_opensees_row("0", "True"), _opensees_row("1", "False")])
    cpu, wall = text.split("Wall time [s]")
    assert cpu.startswith("CPU time [s] (medians; * the analysis within the whole process")
    lines = [ln for ln in cpu.splitlines() if ln.startswith("| 975")]
    assert lines[0] == ("| 975 | 0.5 | 0.5 | 0.5 | 0.5 | 0.5 | 0.5 | 0.5 / 0.5 | 0 / 0 | 0.5 |")
    assert lines[1] == (
        "| 975 | 0.5 | 0.5* (no equilibrium) | - | 0.5 | 0.5 | - | 0.5 / 0.5 | 0 / 0 | - |"
    )
    assert wall.count("| 975 | 0.5 | 0.5 | 0.5 | 0.5 | 7 |") == 2


def test_every_table_has_a_column_per_header():
    rows = [{"system": "UmfPack", "ok": "2", "iterations": "9", "analyze_s": "1e-4"}]
    rows[0].update(diff_same_law="0.001", diff_no_pretension="0")
    text = table.check(rows)
    header, rule, body = text.splitlines()
    assert header.count("|") == rule.count("|") == body.count("|") == 7
    assert body == "| UmfPack | no (2) | 9 | 1.0e-04 | 0.001 | 0 |"
