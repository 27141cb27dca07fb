"""``catenet plot DIR`` for any sweep: the table's columns against the swept keys.

- ``plot_columns(DIR)``: one figure per swept (numeric) key, ``DIR/sweep_<key>.png``: a
  panel per output column that varies (the summary's numbers: deflection, largest
  displacement, tension, compression, reaction, strain, slack edges, peaks, the largest
  utilisation, the natural frequencies of ``--modes``), the rows that succeeded plotted
  against the key, one line per combination of the other keys. An array-valued key
  (``load.point.0.force = [0, 0, -1e3], ...``) gets a figure per element that varies,
  ``KEY[i]``.
- ``plot_chosen(DIR, out, x, ys)``: the columns ``ys`` (``--y``, one panel each) against
  the key ``x`` (``--x``), ``sweep_<columns>_vs_<key>.png``. A name the table does not
  have is a ConfigError that lists what can be plotted.

Axis labels carry units: the outputs' from ``COLUMNS``, a swept key's from its declaration
(``catenet.case.readme.key_unit``), both in the base case's ``units`` (SI, kN-m, N-mm).
"""

from __future__ import annotations

import difflib
import logging
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from catenet.errors import ConfigError
from catenet.model.units import unit_in

log = logging.getLogger(__name__)

# the output columns drawn by default, in this order, with what they are and their
# dimension: "L" length, "F" force, "-" none, "s" time, "Hz", "count", "index"
COLUMNS: dict[str, tuple[str, str]] = {
    "delta": ("delta: probe z-deflection (down)", "L"),
    "max_displacement": ("largest displacement", "L"),
    "max_tension": ("largest tension", "F"),
    "max_compression": ("largest compression (struts)", "F"),
    "max_strain": ("largest strain", "-"),
    "slack_edges": ("slack edges", "count"),
    "max_reaction": ("largest reaction", "F"),
    "max_utilisation": ("largest utilisation F_Ed / F_Rd", "-"),
    "peak_tension": ("peak tension over the run", "F"),
    "peak_displacement": ("peak displacement over the run", "L"),
    "peak_utilisation": ("peak utilisation over the run", "-"),
    "iterations": ("Newton iterations", "count"),
}
# the other numeric columns a user may ask for with --y
MORE: dict[str, tuple[str, str]] = {
    "delta_over_L": ("delta / L", "-"),
    "F_bar": ("F_bar = |sum of loads| / EA", "-"),
    "max_displacement_node": ("node of the largest displacement", "index"),
    "max_tension_edge": ("edge of the largest tension", "index"),
    "max_strain_edge": ("edge of the largest strain", "index"),
    "max_reaction_node": ("node of the largest reaction", "index"),
    "max_utilisation_edge": ("edge of the largest utilisation", "index"),
    **{
        f"{what}_resultant_{c}": (f"{what}s' resultant, {c}", "F")
        for what in ("reaction", "contact")
        for c in "xyz"
    },
    "peak_tension_time": ("time of the peak tension", "s"),
    "probe": ("probe node", "index"),
    "wall_time": ("wall time", "s"),
    "attempts": ("attempts", "count"),
}
#: kept for scripts: the default panels' labels in SI units
OUTPUTS = {c: f"{what} [{ {'L': 'm', 'F': 'N'}.get(d, d) }]" for c, (what, d) in COLUMNS.items()}
OUTPUTS.update({"slack_edges": "slack edges", "iterations": "Newton iterations"})
# not plotted: text and flags
SKIP = {"converged", "error", "run_file"}
# units by the case's `units`: force, length
SYSTEMS = {"SI": ("N", "m"), "kN-m": ("kN", "m"), "N-mm": ("N", "mm")}
FORMATS = (".png", ".svg", ".pdf")
ELEMENT = re.compile(r"^(.*)\[(\d+)\]$")


@dataclass
class Table:
    """A sweep's table: its directory, swept ``keys``, ``columns`` (name -> values, one a
    row), which rows succeeded (``ok``), the base case's ``units`` and its geometry kind."""

    directory: Path
    keys: list[str]
    columns: dict[str, list]
    ok: np.ndarray
    units: str = "SI"
    kind: str = ""

    @classmethod
    def read(cls, directory: Path) -> Table:
        import tomllib

        from catenet.sweep import read_journal, read_table

        keys, _, data = read_table(Path(directory))
        header, _ = read_journal(Path(directory))
        base: dict = {}
        if header is not None:
            try:
                base = tomllib.loads(header.get("base_toml") or "")
            except tomllib.TOMLDecodeError:
                base = header.get("base") or {}
        n = len(next(iter(data.values()), []))
        ok = np.array([not e for e in data.get("error", [""] * n)], dtype=bool)
        units = str(base.get("units")) if base.get("units") in SYSTEMS else "SI"
        kind = (base.get("geometry") or {}).get("kind") or ""
        return cls(Path(directory), keys, data, ok, units, str(kind))

    @property
    def rows(self) -> int:
        return len(self.ok)

    # -- what can be plotted -------------------------------------------------------------

    def numeric(self, name: str) -> np.ndarray | None:
        """The column ``name`` as numbers (NaN where a row has none), None when it is
        not numeric or holds arrays."""
        values = self.columns.get(name)
        if values is None or name in SKIP:
            return None
        if any(isinstance(v, list) for v in values):
            return None
        out = np.array([_number(v) for v in values])
        return out if np.isfinite(out).any() else None

    def elements(self, name: str) -> int:
        """The length of the array-valued column ``name`` (0: not one)."""
        values = self.columns.get(name)
        if not values or not all(isinstance(v, list) for v in values):
            return 0
        sizes = {len(v) for v in values}
        return sizes.pop() if len(sizes) == 1 else 0

    def values(self, name: str) -> np.ndarray | None:
        """A column, or element i of an array-valued one (``NAME[i]``), as numbers."""
        m = ELEMENT.match(name)
        if m and m.group(1) in self.columns and self.elements(m.group(1)):
            i = int(m.group(2))
            if i >= self.elements(m.group(1)):
                return None
            return np.array([_number(v[i]) for v in self.columns[m.group(1)]])
        return self.numeric(name)

    def outputs(self) -> list[str]:
        """The numeric output columns (not swept keys)."""
        return [c for c in self.columns if c not in self.keys and self.numeric(c) is not None]

    def axes(self) -> list[str]:
        """The names --x takes: each numeric swept key, each element of an array one."""
        out = []
        for k in self.keys:
            size = self.elements(k)
            if size:
                out += [f"{k}[{i}]" for i in range(size)]
            elif self.numeric(k) is not None:
                out.append(k)
        return out

    # -- labels ----------------------------------------------------------------------------

    def label(self, name: str) -> str:
        """What a column or key is, with its unit in the case's units."""
        force, length = SYSTEMS[self.units]
        m = ELEMENT.match(name)
        base = m.group(1) if m else name
        if base in self.keys:
            from catenet.case.readme import key_unit

            unit = key_unit(base)
            unit = unit_in(unit, self.units) if unit else ""
            return f"{name} [{unit}]" if unit else name
        if re.fullmatch(r"f\d+", name):
            return f"natural frequency {name} [Hz]"
        what, dim = {**COLUMNS, **MORE}.get(name, (name, ""))
        unit = {"L": length, "F": force}.get(dim, dim)
        if unit in ("count", "index", ""):
            return what
        return f"{what} [{unit}]"

    def listing(self) -> str:
        """What can be plotted, for a message."""
        arrays = [f"{c}[0..{self.elements(c) - 1}]" for c in self.columns if self.elements(c)]
        outputs = [c for c in self.outputs() if c not in self.keys]
        return (
            f"swept keys (--x): {', '.join(self.axes()) or 'none with numbers'}; "
            f"columns (--y): {', '.join(outputs + arrays) or 'none with numbers yet'}"
        )

    def check(self, name: str, option: str, allowed: list[str]) -> np.ndarray:
        """The values of ``name`` for ``option`` (--x or --y; ``allowed`` the names it
        takes), or a ConfigError that says why not and lists what can be plotted."""
        values = self.values(name) if name in allowed else None
        if values is not None:
            return values
        m = ELEMENT.match(name)
        base = m.group(1) if m else name
        size = self.elements(base)
        if size and not m:
            why = f"its values are arrays: give an element, {name}[0] .. {name}[{size - 1}]"
        elif size:
            why = f"{base} has {size} elements ({base}[0] .. {base}[{size - 1}])"
        elif option == "--x" and name in self.columns:
            why = "not a swept key with numbers (--x takes the swept keys)"
        elif name in self.columns:
            why = "its values are not numbers (or no row has one yet)"
        else:
            close = difflib.get_close_matches(name, allowed, n=1)
            why = "not a column of the sweep's table" + (
                f" (did you mean {close[0]!r}?)" if close else ""
            )
        raise ConfigError(f"{option} {name!r}: {why}. {self.directory}: {self.listing()}")


def _number(v) -> float:
    if isinstance(v, bool) or v is None:
        return math.nan
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


def _key(name: str) -> str:
    """The column of ``name``: KEY of an element KEY[i], else the name."""
    m = ELEMENT.match(name)
    return m.group(1) if m else name


def _file_name(*parts: str) -> str:
    return "sweep_" + "_".join(re.sub(r"[^A-Za-z0-9_.-]+", "_", p) for p in parts) + ".png"


def _groups(table: Table, x_name: str) -> dict[tuple, list[int]]:
    """The rows by the values of the swept keys other than ``x_name``'s."""
    others = [k for k in table.keys if k != _key(x_name)]
    groups: dict[tuple, list[int]] = {}
    for i in range(table.rows):
        groups.setdefault(tuple(str(table.columns[k][i]) for k in others), []).append(i)
    return groups


def _figure(table: Table, x_name: str, panels: list[str], title: str, dpi: int, path: Path):
    """Draws ``panels`` (column names) against ``x_name``, one line per group."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    x = table.values(x_name)
    if x is None:
        raise ConfigError(f"--x {x_name!r}: no numbers to plot against")
    others = [k for k in table.keys if k != _key(x_name)]
    groups = _groups(table, x_name)
    cols = 2 if len(panels) == 4 else min(3, len(panels))
    rows = math.ceil(len(panels) / cols)
    fig = Figure(figsize=(4.6 * cols, 3.6 * rows))
    _margins(fig, cols, rows)
    FigureCanvasAgg(fig)
    for j, name in enumerate(panels):
        y = table.values(name)
        y = np.full(table.rows, np.nan) if y is None else y.copy()
        y[~table.ok] = np.nan
        ax = fig.add_subplot(rows, cols, j + 1)
        ax.grid(True, lw=0.3)
        for g, idx in groups.items():
            order = np.array(sorted(idx, key=lambda i: x[i]))
            name_g = ", ".join(f"{k} = {v}" for k, v in zip(others, g, strict=True))
            ax.plot(x[order], y[order], "o-", ms=3.5, lw=1.2, label=name_g or None)
        ax.set_xlabel(table.label(x_name))
        ax.set_ylabel(table.label(name))
        if j == 0 and others and len(groups) <= 10:
            ax.legend(fontsize="small", loc="best")
    failed = int(np.count_nonzero(~table.ok))
    note = f" ({failed} failed rows left out)" if failed else ""
    fig.suptitle(f"{table.directory.name}: {title}{note}")
    fig.savefig(path, dpi=dpi)
    log.info("wrote %s", path)
    return path


# A panel grid's margins [in]: left of the first column and between columns (a panel's
# tick labels and y label), right, top (the title), bottom and between rows (x label).
# Fixed, not matplotlib's constrained layout, which measured every label again and took
# more than half of the time of a figure of many panels.
LEFT, BETWEEN_COLUMNS, RIGHT, TOP, BOTTOM, BETWEEN_ROWS = 0.85, 0.95, 0.2, 0.45, 0.55, 0.75


def _margins(fig: Any, cols: int, rows: int) -> None:
    width, height = fig.get_size_inches()
    panel_w = (width - LEFT - RIGHT - (cols - 1) * BETWEEN_COLUMNS) / cols
    panel_h = (height - TOP - BOTTOM - (rows - 1) * BETWEEN_ROWS) / rows
    fig.subplots_adjust(
        left=LEFT / width,
        right=1.0 - RIGHT / width,
        top=1.0 - TOP / height,
        bottom=BOTTOM / height,
        wspace=BETWEEN_COLUMNS / panel_w,
        hspace=BETWEEN_ROWS / panel_h,
    )


def _varies(table: Table, name: str) -> bool:
    v = table.values(name)
    if v is None:
        return False
    good = v[table.ok & np.isfinite(v)]
    return bool(good.size) and bool(np.ptp(good) > 0)


def plot_columns(directory: Path, out: Path | None = None, *, dpi: int = 120) -> list[Path]:
    """The figures of the sweep in ``directory`` (written to ``out``, default the
    directory); the paths written (none when no row has a number to draw yet).
    ConfigError for a directory that holds no sweep."""
    table = Table.read(Path(directory))
    out = Path(out) if out is not None else table.directory
    out.mkdir(parents=True, exist_ok=True)
    freqs = sorted((c for c in table.columns if re.fullmatch(r"f\d+", c)), key=lambda c: int(c[1:]))
    panels = [c for c in [*COLUMNS, *freqs] if c in table.columns and _varies(table, c)]
    axes = [a for a in table.axes() if _varies(table, a) or a in table.keys]
    if not axes:
        log.info("%s: no swept key with a number to plot against", directory)
        return []
    return [
        _figure(
            table, key, panels or ["delta"], f"outputs against {key}", dpi, out / _file_name(key)
        )
        for key in axes
    ]


def plot_chosen(
    directory: Path, out: Path | None, x: str | None, ys: list[str], *, dpi: int = 120
) -> list[Path]:
    """The columns ``ys`` (each a panel; none: every output that varies) against the
    swept key ``x`` (None: each swept key), ``sweep_<columns>_vs_<key>.png`` in ``out``
    (a directory, default the sweep's; or a figure file .png, .svg, .pdf when one figure
    is drawn). ConfigError naming a column or key the table lacks, with the listing."""
    table = Table.read(Path(directory))
    allowed_y = table.outputs() + table.axes()
    for y in ys:
        table.check(y, "--y", allowed_y)
    axes = table.axes()
    if x is not None:
        table.check(x, "--x", axes)
        chosen = [x]
    else:
        chosen = [a for a in axes if _varies(table, a)] or axes
        if not chosen:
            raise ConfigError(f"--y: {directory}: no swept key with numbers to plot against")
    panels = ys or [c for c in COLUMNS if c in table.columns and _varies(table, c)] or ["delta"]
    target = Path(out) if out is not None else table.directory
    single = target.suffix.lower() in FORMATS
    if single and len(chosen) > 1:
        raise ConfigError(
            f"-o {target}: {len(chosen)} figures (one per swept key): give --x KEY or a directory"
        )
    if not single:
        target.mkdir(parents=True, exist_ok=True)
    elif not target.resolve().parent.is_dir():
        raise ConfigError(f"-o {target}: its directory does not exist")
    written = []
    for key in chosen:
        name = "+".join(panels)[:120]
        path = target if single else target / _file_name(name, "vs", key)
        title = f"{', '.join(panels)} against {key}" if len(panels) < 4 else f"against {key}"
        written.append(_figure(table, key, panels, title, dpi, path))
    return written


def is_square_net_sweep(directory: Path) -> bool:
    """Whether the sweep is the paper's study: a square net swept over geometry.n and
    geometry.alpha (its scaling law and report apply)."""
    from catenet.sweep import read_journal

    header, _ = read_journal(Path(directory))
    base = (header or {}).get("base") or {}
    keys = {k for k, _ in (header or {}).get("params", [])}
    square = (base.get("geometry") or {}).get("kind") == "square_net"
    return square and {"geometry.n", "geometry.alpha"} <= keys
