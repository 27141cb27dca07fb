"""The figure of a modes file's lowest modes (``catenet plot`` on a file that has /modes):
one 3D panel per mode, the equilibrium in grey and the mode at its animation amplitude
(5 % of the case's size for the largest displacement), coloured by the amplitude of
each edge's motion, titled with the frequency, period and dominant direction."""

from __future__ import annotations

import logging
import math
from pathlib import Path

import numpy as np

log = logging.getLogger(__name__)

MOST = 6  # modes drawn at most


def modes_output(out: str | Path) -> Path:
    """The modes figure beside the result figure ``out``: STEM-modes.SUFFIX."""
    out = Path(out)
    return out.with_name(f"{out.stem}-modes{out.suffix}")


def plot_modes(path: str | Path, out: str | Path, *, dpi: int = 150) -> Path | None:
    """Draws the lowest modes of the result file ``path`` into ``out``; None (nothing
    written) where the file has no /modes."""
    from catenet.output.modes import read_modes
    from catenet.output.reader import read_mesh, read_result
    from catenet.plot.figure import in_units

    stored = read_modes(path)
    if stored is None or stored.count == 0:
        return None
    mesh = read_mesh(path)
    fig = figure(stored, mesh.edges, mesh.fixed)
    in_units(fig, read_result(path).case.get("units"))
    fig.savefig(out, dpi=dpi)
    log.info("wrote %s", out)
    return Path(out)


def figure(stored, edges: np.ndarray, fixed: np.ndarray | None):
    """The modes figure (a matplotlib Figure) of a ``catenet.output.modes.StoredModes``."""
    from matplotlib import colormaps
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.colors import Normalize
    from matplotlib.figure import Figure
    from matplotlib.ticker import MaxNLocator
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    count = min(stored.count, MOST)
    cols = min(count, 3)
    rows = math.ceil(count / cols)
    fig = Figure(figsize=(4.6 * cols, 4.2 * rows), layout="constrained")
    FigureCanvasAgg(fig)
    x = stored.x
    amplitude = float(stored.attrs.get("amplitude", 1.0))
    axes = "xyz"
    for k in range(count):
        ax = fig.add_subplot(rows, cols, k + 1, projection="3d")
        phi = stored.shape[k]
        top = float(np.max(np.abs(phi))) or 1.0
        moved = x + (amplitude / top) * phi
        motion = np.linalg.norm(phi, axis=1)[edges].mean(axis=1) / top
        ax.add_collection3d(Line3DCollection(x[edges], colors="0.6", linewidths=0.6))
        lines = Line3DCollection(moved[edges], linewidths=1.3)
        lines.set_array(motion)
        lines.set_cmap(colormaps["plasma"])
        lines.set_norm(Normalize(0.0, 1.0))
        ax.add_collection3d(lines)
        if fixed is not None and np.any(fixed):
            f = x[fixed]
            ax.scatter(f[:, 0], f[:, 1], f[:, 2], color="red", s=6, depthshade=False)
        lo = np.minimum(x.min(axis=0), moved.min(axis=0))
        hi = np.maximum(x.max(axis=0), moved.max(axis=0))
        mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
        half = np.maximum(half, 0.2 * float(half.max()) or 1.0)
        ax.set_xlim(mid[0] - half[0], mid[0] + half[0])
        ax.set_ylim(mid[1] - half[1], mid[1] + half[1])
        ax.set_zlim(mid[2] - half[2], mid[2] + half[2])
        ax.set_box_aspect(tuple(2.0 * half))
        share = stored.direction_share[k]
        ax.set_title(
            f"mode {k + 1}: f = {stored.frequency[k]:.4g} Hz, T = {stored.period[k]:.4g} s"
            f"\nmostly along {axes[int(np.argmax(share))]}",
            fontsize="medium",
        )
        for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
            axis.set_major_locator(MaxNLocator(3))
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_zlabel("z [m]")
    zero = int(stored.attrs.get("zero_modes", 0))
    note = f"; {zero} zero-frequency modes left out" if zero else ""
    fig.suptitle(
        f"lowest {count} natural modes (largest displacement drawn {amplitude:.3g} m){note}"
    )
    return fig
