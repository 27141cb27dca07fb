"""``catenet report``: the tables an engineer hands in, from a result file.

``make_report(path, fmt)`` reads every state of the file (``catenet.output.states``),
builds the tables (``tables``: per cable, support, node set, the loads' balance, the
verdicts; the envelope over the cases) and renders them (``render``: Markdown, CSV
files, HTML with the figures of ``figures``).
"""

from __future__ import annotations

from pathlib import Path

from catenet.errors import ConfigError

__all__ = ["FORMATS", "default_output", "make_report", "write_report"]

FORMATS = ("md", "csv", "html", "xlsx")
SUFFIXES = {
    ".md": "md",
    ".markdown": "md",
    ".html": "html",
    ".htm": "html",
    ".csv": "csv",
    ".xlsx": "xlsx",
}


def default_output(path: Path, fmt: str) -> Path:
    """Where a report goes without -o: beside the result file, STEM.md, STEM.html,
    STEM.xlsx or the directory STEM-csv."""
    path = Path(path)
    if fmt == "csv":
        return path.with_name(f"{path.stem}-csv")
    return path.with_suffix(f".{fmt}")


def format_of(out: Path | None, fmt: str | None) -> str:
    """The report's format: ``fmt`` as given (checked), else from the suffix of ``out``
    (a directory or no known suffix: Markdown, or CSV for a directory); ConfigError for
    an unknown one or a contradiction."""
    if fmt is not None and fmt not in FORMATS:
        raise ConfigError(f"--format {fmt!r}: must be one of {', '.join(FORMATS)}")
    implied = None
    if out is not None and str(out) != "-":
        implied = SUFFIXES.get(Path(out).suffix.lower())
        if implied is None and Path(out).is_dir():
            implied = "csv"
    if fmt is not None and implied is not None and implied != fmt and implied != "csv":
        raise ConfigError(f"-o {out}: its suffix says {implied}, --format says {fmt}: give one")
    return fmt or implied or "md"


def make_report(path: Path, fmt: str):
    """The report of the result file ``path`` in ``fmt``: the text (md, html) or the
    Report itself (csv, xlsx: written by ``write_report``)."""
    from catenet.output.states import read_states
    from catenet.report.render import html_document, markdown
    from catenet.report.tables import build_report, in_units

    states = read_states(path)
    report = build_report(states)
    from catenet.report.lines import lines_tables

    base = [s for s in report.sections if s.kind == "base"]
    if base:  # a dynamic run's lines over time (its /history)
        base[0].tables += lines_tables(states)
    report = in_units(report)
    if fmt == "md":
        return markdown(report)
    if fmt == "html":
        from catenet.report.figures import figures

        return html_document(report, figures(report, states))
    return report


def write_report(path: Path, out: Path | None, fmt: str) -> list[Path]:
    """Writes the report of ``path`` to ``out`` (None: ``default_output``; for csv a
    directory); the files written. ConfigError for a file that is no result file or an
    output that cannot be written."""
    from catenet.report.render import write_csv, write_xlsx

    target = default_output(path, fmt) if out is None else Path(out)
    if fmt == "csv" and target.suffix.lower() == ".csv":
        raise ConfigError(
            f"-o {out}: --format csv writes one file per table: give a directory (e.g. "
            f"{target.with_suffix('')})"
        )
    made = make_report(path, fmt)
    try:
        if fmt == "csv":
            return write_csv(made, target)
        if fmt == "xlsx":
            return [write_xlsx(made, target)]
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(made, encoding="utf-8")
    except OSError as exc:
        raise ConfigError(f"-o {target}: cannot be written: {exc.strerror or exc}") from None
    return [target]
