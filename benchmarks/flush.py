"""What crash-safe result files cost: a 10^3-step dynamic run writing every step.

The same run (a square net of 1 cm edges, n = 22 cables: 7491 unknowns, or n = 10 with
--quick; implicit Euler, h = 1 ms, 1000 steps, a frame per step) is timed, interleaved in
one process, with
- "none": no file (the solve alone),
- "per-frame SWMR": catenet's earlier writer, the file written in place in HDF5's
  SWMR mode and flushed after every frame (killed runs leave a file that ordinary readers
  refuse), re-created here as ``SwmrWriter``,
- "batched, atomic": ``ResultWriter``: frames flushed in batches (at least once a second)
  into a spare copy that replaces the file whole (killed runs leave an ordinary file).
Reported: median wall time, frames, flushes, and the ratio of each to "per-frame SWMR".
The frames of both files are checked to be bitwise equal.
"""

from __future__ import annotations

import sys
from pathlib import Path

if __package__ in (None, ""):  # python benchmarks/flush.py: the repository root on the path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import logging
import math
import tempfile

from benchmarks.common import (
    Study,
    interleaved,
    no_progress,
    pyplot,
    save_figure,
    set_threads,
    warm_up,
    write_csv,
)

log = logging.getLogger(__name__)

NAME = "flush"
TITLE = "Crash-safe result files: cost per run"

STEPS = 1000
CASE = """
title = "flush cost"
[geometry]
kind = "square_net"
n = {n}
alpha = 0.0
size = {size}
edge_length = 0.01
[material]
E = 10e6
radius = 0.01
density = 1000.0
[load]
pressure = 100.0
[solver]
method = "dynamic"
dt = 1e-3
damping = 0.1
t_end = {t_end}
[output]
every = 1
"""


def swmr_writer_class():
    """catenet's earlier writer, for comparison: the trajectory written in place in
    SWMR mode, one frame at a time, flushed after each."""
    import numpy as np

    from catenet.output import ResultWriter
    from catenet.output.reader import LIBVER

    class SwmrWriter(ResultWriter):
        def open(self) -> None:
            import h5py

            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._h5 = h5py.File(self.path, "w", libver=LIBVER)
            self._write_header(self._h5)
            self._create_trajectory(self._h5)
            g = self._h5["trajectory"]
            self._ds = {name: g[name] for name in g}
            self._h5.swmr_mode = True
            self._open = True

        def frame(self, t, x, v=None, tension=None, a=None) -> None:
            data = {"x": np.asarray(x), "tension": self._stored_tension(x, tension)}
            if self.velocities:
                data["v"] = np.zeros_like(x) if v is None else np.asarray(v)
            k = self.frames
            for name, arr in data.items():
                ds = self._ds[name]
                ds.resize(k + 1, axis=0)
                ds[k] = arr
            ds = self._ds["time"]
            ds.resize((k + 1,))
            ds[k] = float(t)
            self._h5.flush()
            self.frames += 1
            self.flushes += 1

        def close(self) -> None:
            if self._open:
                self._ds = {}
                self._h5.close()
                self._open = False

    return SwmrWriter


def run(out_dir: Path, *, quick: bool = False, progress=no_progress, threads: int = 1) -> Study:
    import tomllib

    import h5py
    import numpy as np

    from catenet.case import build, parse_case
    from catenet.output import ResultWriter
    from catenet.solver import path as sv
    from catenet.solver.linear import resolve_backend

    set_threads(threads)
    warm_up()
    n = 10 if quick else 22
    text = CASE.format(n=n, size=n * 0.05, t_end=STEPS * 1e-3)
    scene = build(parse_case(tomllib.loads(text)))
    settings = sv.Settings.of(scene.case.solver, linear=resolve_backend("auto"))
    ws = sv.workspace(scene, settings)
    tmp = Path(tempfile.mkdtemp(prefix="catenet-flush-"))
    writers = {"per-frame SWMR": swmr_writer_class(), "batched, atomic": ResultWriter}

    def one(kind: str):
        def go():
            path = tmp / f"{kind.split()[0].strip(',')}.h5"
            if kind == "none":
                res = sv.solve(scene, settings, workspace=ws)
                return {"steps": res.steps, "frames": 0, "flushes": 0}
            with writers[kind](path, scene, every=1) as w:
                w.frame(0.0, scene.net.nodes, np.zeros_like(scene.net.nodes))

                def on_step(step):
                    w.frame(step.time, step.x, step.v, ws.system.tension(step.x))
                    return False

                res = sv.solve(scene, settings, workspace=ws, on_step=on_step)
            return {"steps": res.steps, "frames": w.frames, "flushes": w.flushes, "path": path}

        return go

    kinds = ("none", "per-frame SWMR", "batched, atomic")
    progress(0, 1, f"n = {n}, {STEPS} steps")
    timings = interleaved({k: one(k) for k in kinds}, repeats=2 if quick else 3)
    progress(1, 1, "")
    frames = {}
    for k in kinds[1:]:
        with h5py.File(timings[k][2]["path"], "r") as h5:
            frames[k] = {name: h5["trajectory"][name][()] for name in ("x", "tension", "v")}
    same = all(
        np.array_equal(frames[kinds[1]][name], frames[kinds[2]][name]) for name in frames[kinds[1]]
    )
    base = timings["per-frame SWMR"][0]
    rows = []
    for k in kinds:
        median, times, info = timings[k]
        rows.append(
            {
                "scheme": k,
                "n": n,
                "dofs": ws.system.n_free,
                "steps": info["steps"],
                "frames": info["frames"],
                "flushes": info["flushes"],
                "wall_seconds": median,
                "wall_min": min(times),
                "ratio_to_per_frame": median / base,
                "frames_equal": same,
            }
        )
    csv = write_csv(rows, Path(out_dir) / f"{NAME}.csv")
    fig = figure(rows, out_dir)
    study = Study(NAME, rows, csv, fig)
    for r in rows:
        study.summary.append(
            f"{r['scheme']:<16} {r['wall_seconds']:7.3f} s  {r['frames']:5d} frames  "
            f"{r['flushes']:5d} flushes  ratio {r['ratio_to_per_frame']:.3f}"
        )
    new = rows[2]["ratio_to_per_frame"]
    extra = (rows[2]["wall_seconds"] - rows[0]["wall_seconds"]) / rows[0]["wall_seconds"]
    study.findings.append(
        f"batched, atomic / per-frame SWMR = {new:.3f} on {STEPS} steps of "
        f"{rows[0]['dofs']} unknowns "
        f"({rows[2]['flushes']} flushes; writing adds {100 * extra:.1f} % to the solve); "
        f"frames bitwise equal: {'yes' if same else 'NO'}"
    )
    if not same or not math.isfinite(new) or new > 1.10:
        log.warning("flush study: %s", study.findings[-1])
    for p in tmp.iterdir():
        p.unlink()
    tmp.rmdir()
    return study


def figure(rows, out_dir):
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 3.2))
    names = [r["scheme"] for r in rows]
    walls = [r["wall_seconds"] for r in rows]
    bars = ax.barh(names, walls, color=["#999999", "#0072B2", "#E69F00"])
    for bar, r in zip(bars, rows, strict=True):
        ax.text(
            bar.get_width(),
            bar.get_y() + bar.get_height() / 2,
            f" {r['wall_seconds']:.2f} s, ratio {r['ratio_to_per_frame']:.2f}",
            va="center",
        )
    ax.set_xlabel("wall time of the run [s] (median)")
    ax.set_title(f"{rows[0]['steps']} dynamic steps, a frame per step ({rows[0]['dofs']} unknowns)")
    ax.set_xlim(0, max(walls) * 1.6)
    fig.tight_layout()
    return save_figure(fig, out_dir, NAME)


if __name__ == "__main__":
    from benchmarks.__main__ import script

    script(NAME)
