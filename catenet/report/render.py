"""A report (``catenet.report.tables.Report``) as Markdown, HTML (with its figures
embedded as base64 PNG) or CSV files.

CSV: one file per kind of table in a directory, ``cables.csv``, ``supports.csv``,
``displacements.csv``, ``balance.csv``, ``envelope_cables.csv``,
``envelope_supports.csv``, ``envelope_displacements.csv`` and ``verdicts.csv``; each
row starts with the state it belongs to (``state``: "base state", a load case's or a
combination's name, "envelope") and its ``kind``, so that each file is one table for
pandas. Numbers are written in full (``repr``), NaN as an empty field.
"""

from __future__ import annotations

import csv
import html
import math
from pathlib import Path

from catenet.report.tables import Report, Table

FORMATS = ("md", "csv", "html", "xlsx")


def cell(v) -> str:
    """A value as a report shows it: 6 significant digits, "n/a" for NaN or None (not
    known)."""
    if v is None:
        return "n/a"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        if math.isnan(v):
            return "n/a"
        return f"{v:.6g}"
    return str(v)


def _none(sec) -> str:
    """What a section without warnings says: none, or that the file keeps none."""
    return "none" if sec.recorded or sec.kind == "envelope" else "not recorded in the file"


def _md_escape(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def markdown_table(t: Table) -> list[str]:
    lines = [f"#### {t.title}", ""]
    if not t.rows:
        return [*lines, "(none)", ""]
    lines.append("| " + " | ".join(_md_escape(c) for c in t.columns) + " |")
    lines.append("|" + "|".join("---" if k == 0 else "---:" for k in range(len(t.columns))) + "|")
    for row in t.rows:
        lines.append("| " + " | ".join(_md_escape(cell(v)) for v in row) + " |")
    if t.note:
        lines += ["", f"*{t.note}*"]
    return [*lines, ""]


def markdown(report: Report) -> str:
    """The report as a Markdown document."""
    lines = [f"# {report.title}", ""]
    lines += [f"- **{k}**: {_md_escape(v)}" for k, v in report.about.items()]
    lines.append("")
    for sec in report.sections:
        lines += [f"## {sec.heading}", ""]
        lines += [f"- **{k}**: {_md_escape(v)}" for k, v in sec.verdict.items()]
        if sec.warnings:
            lines.append(f"- **warnings** ({len(sec.warnings)}):")
            lines += [f"    - {_md_escape(w)}" for w in sec.warnings]
        else:
            lines.append(f"- **warnings**: {_none(sec)}")
        lines.append("")
        for t in sec.tables:
            lines += markdown_table(t)
    return "\n".join(lines).rstrip() + "\n"


def _csv_value(v):
    if v is None:
        return ""
    if isinstance(v, float):
        return "" if math.isnan(v) else repr(v)
    return v


def sheets(report: Report) -> list[tuple[str, list[list]]]:
    """The report's tables as sheets: per kind of table (its key) a header row and the
    rows of every state (columns ``state`` and ``kind`` first), then ``verdicts``."""
    tables: dict[str, tuple[tuple[str, ...], list[list]]] = {}
    for sec in report.sections:
        for t in sec.tables:
            columns, rows = tables.setdefault(t.key, (("state", "kind", *t.columns), []))
            rows += [[sec.name, sec.kind, *row] for row in t.rows]
    verdicts = [["state", "kind", "converged", "stability", "detail", "warnings"]]
    for sec in report.sections:
        v = sec.verdict
        detail = v.get("error") or v.get("message") or ""
        verdicts.append(
            [sec.name, sec.kind, v.get("converged", ""), v.get("stability", ""), detail]
            + ["\n".join(sec.warnings)]
        )
    out = [(key, [list(columns), *rows]) for key, (columns, rows) in tables.items()]
    return [*out, ("verdicts", verdicts)]


def write_csv(report: Report, directory: Path) -> list[Path]:
    """The report's tables as CSV files in ``directory`` (created); the files written."""
    directory.mkdir(parents=True, exist_ok=True)
    return [_write(directory / f"{key}.csv", rows) for key, rows in sheets(report)]


def write_xlsx(report: Report, path: Path) -> Path:
    """The report's tables as one Excel workbook (openpyxl), a sheet per kind of table as
    in the CSV files: numbers as numbers (NaN: an empty cell), a frozen header row."""
    from openpyxl import Workbook

    book = Workbook()
    book.remove(book.active)
    for key, rows in sheets(report):
        sheet = book.create_sheet(key[:31])  # Excel's longest sheet name
        for row in rows:
            sheet.append([_xlsx_value(v) for v in row])
        sheet.freeze_panes = "A2"
    path.parent.mkdir(parents=True, exist_ok=True)
    book.save(path)
    return path


def _xlsx_value(v):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return None
    if isinstance(v, (bool, int, float, str)):
        return v
    return str(v)


def _write(path: Path, rows: list[list]) -> Path:
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        for row in rows:
            w.writerow([_csv_value(v) for v in row])
    return path


def html_document(report: Report, figures: dict[str, list[str]]) -> str:
    """The report as one HTML page; ``figures``: per section name, base64 PNGs shown
    under its heading ("" key: under the title)."""
    e = html.escape
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>{e(report.title)}</title>",
        "<style>body{font-family:sans-serif;max-width:72em;margin:2em auto;padding:0 1em}"
        "table{border-collapse:collapse;margin:0.5em 0 1.5em}"
        "td,th{border:1px solid #ccc;padding:0.2em 0.6em}td.n{text-align:right}"
        "img{max-width:100%}.note{color:#555;font-size:90%}</style>",
        "</head><body>",
        f"<h1>{e(report.title)}</h1>",
        _dl(report.about),
    ]
    parts += [_img(png) for png in figures.get("", [])]
    for sec in report.sections:
        parts.append(f"<h2>{e(sec.heading)}</h2>")
        parts.append(_dl(sec.verdict))
        if sec.warnings:
            items = "".join(f"<li>{e(w)}</li>" for w in sec.warnings)
            parts.append(f"<p>warnings ({len(sec.warnings)}):</p><ul>{items}</ul>")
        else:
            parts.append(f"<p>warnings: {_none(sec)}</p>")
        parts += [_img(png) for png in figures.get(sec.name, [])]
        parts += [_html_table(t) for t in sec.tables]
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


def _dl(items: dict[str, str]) -> str:
    e = html.escape
    return "<dl>" + "".join(f"<dt>{e(k)}</dt><dd>{e(v)}</dd>" for k, v in items.items()) + "</dl>"


def _img(png: str) -> str:
    return f'<p><img alt="figure" src="data:image/png;base64,{png}"></p>'


def _html_table(t: Table) -> str:
    e = html.escape
    out = [f"<h4>{e(t.title)}</h4>"]
    if not t.rows:
        return out[0] + "<p>(none)</p>"
    out.append("<table><tr>" + "".join(f"<th>{e(c)}</th>" for c in t.columns) + "</tr>")
    for row in t.rows:
        cells = "".join(
            f'<td class="n">{e(cell(v))}</td>'
            if isinstance(v, (int, float))
            else f"<td>{e(cell(v))}</td>"
            for v in row
        )
        out.append(f"<tr>{cells}</tr>")
    out.append("</table>")
    if t.note:
        out.append(f'<p class="note">{e(t.note)}</p>')
    return "".join(out)
