"""What form finding by targets reports: each target's achieved value (``rows``), the
result file's ``/result/targets/<k>`` groups and ``/result/force_density`` (``write``),
and the lines of the written case's header (``header_lines``).

``/result/targets/<k>`` (k: the target's index in [[target]]) has the attrs ``kind``
("x", "y", "z", "point", "surface", "tension", "length", "reaction" or "reaction_x" ...),
``about`` (what it is about, as the summary says), ``nodes``, ``edges`` or ``cables`` (the
nodes, supports included, the edges or the cables it concerns), ``target`` (one value per
node, edge or cable; a range: ``low`` and ``high``), ``achieved`` (the same shape), ``miss`` (the
largest |miss|, 0 within a range), ``weight``, ``hard`` and ``met`` (to formfind.tol);
``/result/targets`` itself: ``met`` (all), ``message``, ``variables``, ``vary``,
``evaluations`` and ``gradients``; method "elastic", and the force density method where
supports move, add ``found`` (the variables found: rest-length factors, prestresses [N]
or force densities [N/m], then the supports' offsets [m]), ``found_kind`` ("factor",
"prestress", "force_density" or "offset": the offsets alone) and, where named, ``names``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np


@dataclass(frozen=True)
class Row:
    """One target as reported: ``k``, what it is ``about``, its unit, the ``target``
    (lo, hi per row of it), ``achieved`` and ``met``."""

    k: int
    about: str
    kind: str
    unit: str
    where: np.ndarray  # nodes (positions), edges (tensions) or cables (lengths)
    lo: np.ndarray
    hi: np.ndarray
    achieved: np.ndarray
    miss: float
    met: bool
    weight: float
    hard: bool

    def line(self) -> str:
        """``node 'centre' z: -3 m (target -3 m, miss 3.8e-14, met)``."""
        got, want = _shown(self.achieved), _shown(self.lo)
        if not np.array_equal(self.lo, self.hi):
            want = f"[{_shown(self.lo)}, {_shown(self.hi)}]"
        if len(self.where) > 1:
            got += f" ({len(self.where)})"
            if np.ptp(self.lo) > 0 or np.ptp(self.hi) > 0:
                want = "one per node"
        verdict = "met" if self.met else "NOT met"
        u = self.unit
        return f"{self.about}: {got} {u} (target {want} {u}, miss {self.miss:.2g}, {verdict})"


def _shown(v: np.ndarray) -> str:
    """One value, one point, or the range of many."""
    v = np.asarray(v, dtype=np.float64) + 0.0  # (no -0)
    if v.ndim == 2 and v.shape[0] == 1:
        return "[" + ", ".join(f"{c:.6g}" for c in v[0]) + "]"
    if v.size == 1:
        return f"{float(v.ravel()[0]):.6g}"
    lo, hi = float(v.min()), float(v.max())
    return f"{lo:.6g}" if lo == hi else f"{lo:.6g} .. {hi:.6g}"


def rows(design) -> list[Row]:
    """The targets of ``design`` (catenet.formfind.design.Design) as reported."""
    g = design.goals
    miss = design.miss()
    out = []
    for k, t in enumerate(g.targets):
        sel = np.flatnonzero(g.of == k)
        length = t.cable is not None and t.length is not None
        force = (t.cable is not None and not length) or t.support is not None
        where = g.edge[sel] if t.cable is not None else g.node[sel]
        if length:  # (a row per cable: its index)
            where = np.array([g.chains[c][0] for c in g.chain[sel]], dtype=np.int64)
        where = where[: len(sel) // _axes(t)]  # (rows by axis: x of every node, y ...)
        out.append(
            Row(
                k=k,
                about=t.describe(),
                kind=t.kind,
                unit="N" if force else "m",
                where=where,
                lo=_shaped(g.lo[sel], t),
                hi=_shaped(g.hi[sel], t),
                achieved=_shaped(design.achieved[sel], t),
                miss=float(np.max(np.abs(miss[sel]))),
                met=bool(design.met[sel].all()),
                weight=float(t.weight),
                hard=bool(t.hard),
            )
        )
    return out


def _axes(t) -> int:
    """The coordinates (or reaction components) a target gives per node (1 for a
    tension)."""
    if t.support is not None:
        return len(t.components)
    return 3 if t.point is not None else max(len(t.axes), 1)


def _shaped(v: np.ndarray, t) -> np.ndarray:
    """The rows of a target of several coordinates (by axis) as (nodes, axes); of one
    coordinate or a tension, as they are."""
    n = _axes(t)
    return v.reshape(n, -1).T.copy() if n > 1 else v.copy()


def write(path: str | Path, found) -> None:
    """Adds /result/targets and /result/force_density to the result file ``path``."""
    import h5py

    from catenet.output.files import copy_atomically
    from catenet.output.reader import LIBVER

    path = Path(path)
    d = found.design
    tmp = path.with_name(f".{path.name}.targets.{os.getpid()}")
    copy_atomically(path, tmp)
    try:
        with h5py.File(tmp, "r+", libver=LIBVER) as h5:
            h5["result"].create_dataset("force_density", data=np.asarray(found.q))
            group = h5["result"].create_group("targets")
            for key, value in (
                ("met", d.all_met),
                ("message", d.message),
                ("variables", d.variables),
                ("vary", d.vary),
                ("evaluations", d.evaluations),
                ("gradients", d.gradients),
            ):
                group.attrs[key] = value
            if "values" in d.extra:  # method "elastic": the variables found, by name
                group.attrs["found"] = np.asarray(d.extra["values"], dtype=np.float64)
                group.attrs["found_kind"] = d.extra["kind"]
                if d.extra["names"]:
                    group.attrs["names"] = [str(n) for n in d.extra["names"]]
            for row in rows(d):
                _write_row(group.create_group(str(row.k)), row)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _write_row(g, row: Row) -> None:
    g.attrs["kind"] = row.kind
    g.attrs["about"] = row.about
    where = {"tension": "edges", "length": "cables"}.get(row.kind, "nodes")
    g.attrs[where] = row.where.astype(np.int64)
    if np.array_equal(row.lo, row.hi):
        g.attrs["target"] = row.lo
    else:
        g.attrs["low"], g.attrs["high"] = row.lo, row.hi
    g.attrs["achieved"] = row.achieved
    g.attrs["miss"] = row.miss
    g.attrs["weight"] = row.weight
    g.attrs["hard"] = row.hard
    g.attrs["met"] = row.met


def header_lines(found) -> list[str]:
    """The targets as the written case's header names them."""
    d = found.design
    what = "force densities"
    if found.method == "elastic":
        what = "prestresses" if d.extra.get("kind") == "prestress" else "rest-length factors"
    by = "edge" if d.vary == "edges" else "cable"
    moved = int(d.extra.get("moved", 0))
    varied = [f"{d.variables - moved} {what} by {by}"] if d.variables > moved else []
    if moved:
        varied.append(f"{moved} support offset{'s' if moved > 1 else ''}")
    lines = [f"Targets ({d.message}; {' and '.join(varied)}):"]
    lines += [f"  target[{r.k}] {r.line()}" for r in rows(d)]
    if moved:
        names, values = d.extra["names"][-moved:], d.extra["values"][-moved:]
        lines += [f"  moved {n}: {float(v):+.9g} m" for n, v in zip(names, values, strict=True)]
    return lines


__all__ = ["Row", "header_lines", "rows", "write"]
