"""The moving spheres of a result file in ``catenet plot``'s figure (``catenet.plot.figure``):
each ball at its final place (a shaded sphere in the 3D view, a disc in the side view),
the path of its centre, and, in the time panel of a dynamic run, the drop of its centre.
A file without moving spheres draws nothing."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from catenet.output.bodies import Bodies


class Balls:
    """The balls of a result ``res`` with displacements drawn ``scale`` times."""

    def __init__(self, res, scale: float = 1.0):
        from catenet.output.bodies import read_bodies

        self.b: Bodies | None
        try:
            self.b = read_bodies(res.path)
        except (OSError, KeyError, ValueError):
            self.b = None
        if self.b is not None and not len(self.b):
            self.b = None
        if self.b is None:
            return
        ref = res.mesh.nodes[self.b.node]
        self.center = ref + scale * (res.x[self.b.node] - ref)  # (B, 3)
        path = self.b.center if len(self.b.times) else self.center[None]
        self.path = ref + scale * (path - ref)  # (F, B, 3)
        self.ref = ref

    def extent(self) -> list[np.ndarray]:
        """Points the views' limits must include: each ball's box along its path."""
        if self.b is None:
            return []
        r = self.b.radius[None, :, None]
        return [self.path - r, self.path + r]

    def draw3d(self, ax) -> None:
        if self.b is None:
            return
        u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 25), np.linspace(0, np.pi, 13))
        for c, r in zip(self.center, self.b.radius, strict=True):
            ax.plot_surface(
                c[0] + r * np.cos(u) * np.sin(v),
                c[1] + r * np.sin(u) * np.sin(v),
                c[2] + r * np.cos(v),
                color="0.55",
                alpha=0.35,
                linewidth=0,
                shade=True,
            )
        for k in range(len(self.b)):
            p = self.path[:, k]
            ax.plot(p[:, 0], p[:, 1], p[:, 2], ":", color="k", lw=0.8)

    def draw2d(self, ax, h: int) -> None:
        if self.b is None:
            return
        from matplotlib.patches import Circle

        for k, (c, r) in enumerate(zip(self.center, self.b.radius, strict=True)):
            kind = "ball on a path" if self.b.prescribed[k] else f"ball, {self.b.mass[k]:.3g} kg"
            ax.add_patch(Circle((c[h], c[2]), r, color="0.55", alpha=0.45, zorder=1, label=kind))
            p = self.path[:, k]
            ax.plot(p[:, h], p[:, 2], ":", color="k", lw=0.8, zorder=4, label="its centre's path")

    def draw_series(self, ax) -> None:
        """The drop of each ball's centre (positive down) against time."""
        if self.b is None or len(self.b.times) < 2:
            return
        for line in ax.get_lines()[:1]:
            if line.get_label().startswith("_"):
                line.set_label("probe node")
        for k in range(len(self.b)):
            drop = self.ref[k, 2] - self.b.center[:, k, 2]
            ax.plot(self.b.times, drop, "--", color="0.4", lw=1.0, label=f"ball {k}: centre drop")
        ax.legend(loc="best", fontsize="small")
