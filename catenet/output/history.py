"""A dynamic run's histories in its result file (contract §7): a row at every accepted
time step, not only at the stored frames, kept compactly (a few numbers a step).

```
/history/time                (S,) [s]: the start, then every accepted time step
/history/reaction            (S, Ns, 3) [N]: the force each support node exerts on the net
/history/reaction_nodes      (Ns,) int64: those nodes (fixed, moved, rollers, sliders, springs)
/history/contact             (S, K, 3) [N]: the total force of each obstacle, ball or free
                             body on the net; attrs obstacles (K,) their indices k
                             (``obstacle[k]``), names, kinds
/history/cable_end_tension   (S, C, 2) [N]: the tension of each named cable's end edges
                             (its first edge, its last); attrs cable_names (C,), edges (C, 2)
/history/cable_tension_range (S, C, 2) [N]: each named cable's least and largest edge
                             tension
/history/anchor_uplift       (S, C) [deg]: each named cable's angle above the horizontal
                             at its anchor (its end lower in the given geometry)
/history/touchdown           (S, C) [m]: the unstretched arc length from each named
                             cable's anchor to its touchdown point (runs with obstacles)
```

(``catenet.model.lines``: the line's path from its anchor, uplift and touchdown.)

A dataset is there only where the run has what it counts (supports, obstacles or
bodies, named cables). The rows gather in memory and reach the file with the trajectory's
frames, in the same flushes (``catenet.output.writer``): a run that fails or is
interrupted keeps every row up to its last good state, a killed one every row up to the
last flush. ``time`` is written last: a row counts once its time is there
(``read_history`` reads as many rows as ``time`` has).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from catenet.errors import ConfigError
from catenet.output.files import check_finite, read_text

GROUP = "history"
ROWS_PER_CHUNK = 256  # rows of a chunk (fewer where a row is large)
CHUNK_BYTES = 2**20
UNITS = {"anchor_uplift": "deg", "touchdown": "m"}  # the others' [N]

__all__ = ["GROUP", "HistoryLayout", "HistoryLog", "read_history"]


@dataclass(frozen=True)
class HistoryLayout:
    """What a run's history holds: the support nodes (Ns,), the obstacles and bodies
    (their indices k, names and kinds) and the named cables with their end edges (C, 2)."""

    reaction_nodes: np.ndarray
    obstacles: tuple[int, ...] = ()
    names: tuple[str, ...] = ()
    kinds: tuple[str, ...] = ()
    cable_names: tuple[str, ...] = ()
    cable_edges: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int64))
    grounds: bool = False  # touchdown points recorded (the run has obstacles)

    def shapes(self) -> dict[str, tuple[int, ...]]:
        """Each dataset's row shape (only those the run has)."""
        out: dict[str, tuple[int, ...]] = {}
        if len(self.reaction_nodes):
            out["reaction"] = (len(self.reaction_nodes), 3)
        if self.obstacles:
            out["contact"] = (len(self.obstacles), 3)
        if self.cable_names:
            c = len(self.cable_names)
            out.update(cable_end_tension=(c, 2), cable_tension_range=(c, 2), anchor_uplift=(c,))
            if self.grounds:
                out["touchdown"] = (c,)
        return out


class HistoryLog:
    """The rows of a run's history not yet in the file, and how they are written."""

    def __init__(self, layout: HistoryLayout):
        self.layout = layout
        self.shapes = layout.shapes()
        self.rows = 0  # in the file
        self.pending: list[tuple[float, dict[str, np.ndarray]]] = []

    def take(self, t: float, row: dict[str, np.ndarray]) -> None:
        """A row at time t (copied); raises OutputError where it is not finite."""
        data = {name: np.array(row[name], dtype=np.float64) for name in self.shapes}
        for name, arr in data.items():
            if arr.shape != self.shapes[name]:
                raise ValueError(f"history {name}: shape {arr.shape}, not {self.shapes[name]}")
            check_finite(f"history {name}", arr, float(t))
        self.pending.append((float(t), data))

    def published(self, n: int) -> None:
        """The first n pending rows are in the file now."""
        self.rows += n
        self.pending = self.pending[n:]

    def create(self, h5) -> None:
        """The empty /history group in a new file."""
        import h5py

        g = h5.create_group(GROUP)
        g.create_dataset("time", shape=(0,), maxshape=(None,), dtype="f8", chunks=(1024,))
        g["time"].attrs["unit"] = "s"
        layout = self.layout
        g.create_dataset("reaction_nodes", data=np.asarray(layout.reaction_nodes, np.int64))
        for name, tail in self.shapes.items():
            size = 8 * int(np.prod(tail))
            rows = max(1, min(ROWS_PER_CHUNK, CHUNK_BYTES // size))
            g.create_dataset(
                name,
                shape=(0, *tail),
                maxshape=(None, *tail),
                dtype="f8",
                chunks=(rows, *tail),
                compression="gzip",
                compression_opts=4,
                shuffle=True,
            )
            g[name].attrs["unit"] = UNITS.get(name, "N")
        strings = h5py.string_dtype()
        if "contact" in g:
            c = g["contact"]
            c.attrs["obstacles"] = np.asarray(layout.obstacles, dtype=np.int64)
            c.attrs["names"] = np.array(layout.names, dtype=strings)
            c.attrs["kinds"] = np.array(layout.kinds, dtype=strings)
        for name in ("cable_end_tension", "cable_tension_range", "anchor_uplift", "touchdown"):
            if name in g:
                g[name].attrs["cable_names"] = np.array(layout.cable_names, dtype=strings)
        if "cable_end_tension" in g:
            g["cable_end_tension"].attrs["edges"] = np.asarray(layout.cable_edges, dtype=np.int64)

    def append(self, h5, batch, n0: int, held: list) -> None:
        """Appends ``batch`` (rows n0, n0 + 1, ...) to the file's /history; ``held``
        keeps the datasets open as long as the file (``catenet.output.files.detach``)."""
        if not batch:
            return
        g = h5[GROUP]
        n1 = n0 + len(batch)
        for name in self.shapes:
            held.append(ds := g[name])
            ds.resize(n1, axis=0)
            ds[n0:n1] = np.stack([row[name] for _, row in batch])
        held.append(ds := g["time"])
        ds.resize((n1,))
        ds[n0:n1] = [t for t, _ in batch]  # last: a row counts once its time is there


@dataclass
class History:
    """A result file's history (``read_history``): ``time`` (S,), ``reaction`` (S, Ns, 3)
    at ``reaction_nodes``, ``contact`` (S, K, 3) of ``obstacles`` (their ``names``),
    ``cable_end_tension`` (S, C, 2) of ``cable_names``, their ``cable_tension_range`` (S, C, 2),
    ``anchor_uplift`` (S, C) and ``touchdown`` (S, C); empty arrays where the run has none."""

    time: np.ndarray
    reaction: np.ndarray
    reaction_nodes: np.ndarray
    contact: np.ndarray
    obstacles: np.ndarray
    names: list[str]
    cable_end_tension: np.ndarray
    cable_names: list[str]
    cable_tension_range: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 2)))
    anchor_uplift: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    touchdown: np.ndarray | None = None  # None: not recorded (no obstacle)


def read_history(path: str | Path) -> History | None:
    """The history in the result file ``path`` (None: it has none, a static run's or a
    file written before histories); rows up to the last one with its time. Raises
    ConfigError for a file that cannot be read."""
    import h5py

    try:
        with h5py.File(path, "r") as h5:
            if GROUP not in h5:
                return None
            g = h5[GROUP]
            t = np.asarray(g["time"][:], dtype=np.float64)
            s = len(t)

            def rows(name: str, tail: tuple[int, ...]) -> np.ndarray:
                return np.asarray(g[name][:s]) if name in g else np.zeros((s, *tail))

            def names(name: str, attr: str) -> list[str]:
                if name not in g:
                    return []
                return [read_text(v) for v in g[name].attrs[attr]]

            contact = g["contact"] if "contact" in g else None
            return History(
                time=t,
                reaction=rows("reaction", (0, 3)),
                reaction_nodes=np.asarray(g["reaction_nodes"][:], dtype=np.int64),
                contact=rows("contact", (0, 3)),
                obstacles=np.asarray(
                    contact.attrs["obstacles"] if contact is not None else [], np.int64
                ),
                names=names("contact", "names"),
                cable_end_tension=rows("cable_end_tension", (0, 2)),
                cable_names=names("cable_end_tension", "cable_names"),
                cable_tension_range=rows("cable_tension_range", (0, 2)),
                anchor_uplift=rows("anchor_uplift", (0,)),
                touchdown=rows("touchdown", (0,)) if "touchdown" in g else None,
            )
    except (OSError, KeyError, ValueError) as exc:
        raise ConfigError(f"{path}: its /history cannot be read: {exc}") from None
