"""Fixed and moving obstacles in a result file: their surfaces, and where the moving
ones are at every frame, for ParaView (the XDMF sidecar, ``catenet.output.xdmf``) and
for readers (``read_obstacles``).

Each ``[[obstacle]]`` but a moving sphere (a node of the net: ``catenet.output.bodies``)
is a closed triangle surface with outward normals, as ``catenet.output.surfaces``
tessellates it (``catenet plot`` draws the same): a box 12 triangles, a sphere and a
capsule of 36 meridians, a mesh as its file reads, a plane the rectangle covering the
initial net 1.5 times in it. Obstacle k (its index among the case's ``[[obstacle]]``):

```
/mesh/obstacles                      attrs: count
/mesh/obstacles/<k>/vertices         (V, 3) float64 [m]: the surface at t = 0
/mesh/obstacles/<k>/triangles        (T, 3) int64: vertex indices, outward
/mesh/obstacles/<k>                  attrs: kind, obstacle (k), moving (bool),
                                     origin (3,): the point it turns about (moving ones)
```

An obstacle on a prescribed motion (dynamic runs) also has, for every trajectory frame
(written with the frame, so a killed run's file has as many as /trajectory/time), its
pose and its surface there, and the same at /result's time:

```
/trajectory/obstacles/<k>/center     (F, 3) c(t): where the origin is
/trajectory/obstacles/<k>/rotation   (F, 3, 3) R(t): x(t) = c(t) + R(t) (x(0) - origin)
/trajectory/obstacles/<k>/vertices   (F, V', 3) the surface at the frame's time
/result/obstacles/<k>/{center, rotation, vertices}   the same at the final time
```

A free rigid body (``catenet.scene.rigid``) is stored as a moving one, its pose read from
the state (its four nodes, ``catenet.terms.rigid.BodyFrame``; the origin is its centre of
mass at t = 0), with more:

```
/mesh/obstacles/<k>                  attrs: mass [kg], free (True)
/mesh/obstacles/<k>/inertia          (3, 3) [kg m^2] about the centre of mass, body axes
/mesh/obstacles/<k>/axes             (3, 3) the body axes at t = 0 (columns, world frame)
/trajectory/obstacles/<k>/velocity   (F, 3) of the centre of mass [m/s]
/trajectory/obstacles/<k>/angular_velocity  (F, 3) [rad/s], world frame
/result/obstacles/<k>/{velocity, angular_velocity}   the same at the final time
```

(zeros where the file keeps no velocities: static runs). The pose is the solver's
(``catenet.terms.moving``, ``catenet.terms.rigid``). A surface of more than
``frame_cap(n)`` = max(FRAME_VERTICES, the net's node count) vertices is stored per frame
simplified (vertex clustering, at most that many vertices; a warning says so) with its
own triangles ``/mesh/obstacles/<k>/frame_triangles``, so that the frames never take much
more room than the net's own positions; the whole surface stays in /mesh and the exact
pose in center and rotation.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from catenet.output.files import read_text
from catenet.output.reader import open_result, trajectory_length

if TYPE_CHECKING:
    from catenet.case.parse import Case
    from catenet.scene.scene import Scene
    from catenet.solver.result import Result

log = logging.getLogger(__name__)

GROUP = "obstacles"  # in /mesh, /trajectory and /result
FRAME_VERTICES = 4096  # a moving surface is stored per frame with at most
# max(FRAME_VERTICES, net nodes) vertices
POSE_CHUNK = 256  # frames per chunk of center and rotation
FREE_SETS = ("velocity", "angular_velocity")  # a free body's more per frame

__all__ = ["FRAME_VERTICES", "ObstacleGrid", "Obstacles", "StoredObstacle", "read_obstacles"]


def frame_cap(n_nodes: int) -> int:
    """The most vertices a moving obstacle's surface is stored with per frame."""
    return max(FRAME_VERTICES, int(n_nodes))


def frame_values(case: Case, n_nodes: int) -> int:
    """The float64 values per trajectory frame that the moving obstacles of ``case`` add
    (pose and surface; at most ``frame_cap`` vertices each)."""
    from catenet.output.surfaces import surface

    cap, total = frame_cap(n_nodes), 0
    for k, obs in enumerate(case.obstacles):
        moves = obs.rigid_motion or obs.free
        shape = surface(obs.to_dict(), k) if moves else None
        if shape is not None:  # (a moving sphere is a node of the net: no surface)
            total += 3 * min(len(shape.vertices), cap) + 12
    return total


def simplify(V, T, cap: int) -> tuple[np.ndarray, np.ndarray]:
    """A surface of at most ``cap`` vertices resembling (V, T): vertices merged per cell
    of a uniform grid (each the mean of its own), the grid coarsened until few enough
    remain; triangles that collapse or repeat are dropped."""
    V, T = np.asarray(V, dtype=np.float64), np.asarray(T, dtype=np.int64)
    lo = V.min(axis=0)
    h = float(np.ptp(V, axis=0).max()) / math.sqrt(cap) or 1.0
    while True:
        key = np.floor((V - lo) / h).astype(np.int64)
        _, cluster = np.unique(key, axis=0, return_inverse=True)
        cluster = cluster.reshape(-1)
        if cluster.max() + 1 <= cap:
            break
        h *= 1.25
    count = np.bincount(cluster)
    W = np.zeros((len(count), 3))
    np.add.at(W, cluster, V)
    W /= count[:, None]
    T = cluster[T]
    T = T[(T[:, 0] != T[:, 1]) & (T[:, 1] != T[:, 2]) & (T[:, 2] != T[:, 0])]
    _, first = np.unique(np.sort(T, axis=1), axis=0, return_index=True)
    T = T[np.sort(first)]
    used, T = np.unique(T, return_inverse=True)
    return np.ascontiguousarray(W[used]), np.ascontiguousarray(T.reshape(-1, 3))


@dataclass(frozen=True)
class ObstacleGrid:
    """What the sidecar shows of obstacle ``index``: its surface's ``vertices`` and
    ``triangles`` counts (those stored per frame for a moving one) and whether its
    triangles per frame are ``frame_triangles`` (a simplified surface)."""

    index: int
    kind: str
    moving: bool
    vertices: int
    triangles: int
    simplified: bool = False

    @property
    def name(self) -> str:
        return f"obstacle[{self.index}] {self.kind}"

    def path(self, name: str) -> str:
        """The HDF5 path of one of its datasets in /mesh."""
        return f"/mesh/{GROUP}/{self.index}/{name}"

    @property
    def topology(self) -> str:
        return self.path("frame_triangles" if self.simplified else "triangles")

    def frame(self, k: int) -> str:
        """Its vertices at frame k: the view of /trajectory (``catenet.output.xdmf``)."""
        return f"/xdmf/{GROUP}/{self.index}/vertices/{k}"

    @property
    def final(self) -> str:
        return f"/result/{GROUP}/{self.index}/vertices"


class _Item:
    """One obstacle as the writer stores it."""

    def __init__(self, surface, cap: int, body=None):
        self.surface = surface
        self.body = body  # a free body (catenet.scene.rigid.FreeBody), else None
        self.vertices = np.ascontiguousarray(surface.vertices, dtype=np.float64)
        self.triangles = surface.triangles
        self.shown, self.shown_triangles = self.vertices, self.triangles
        self.moving = surface.moving or body is not None
        self.simplified = self.moving and len(self.vertices) > cap
        if self.simplified:
            self.shown, self.shown_triangles = simplify(self.vertices, self.triangles, cap)
            log.warning(
                "%s: a moving surface of %d vertices: its frames in the result file hold a "
                "simplified one of %d (at most max(%d, the net's nodes)); the whole surface "
                "is in /mesh/%s/%d and its pose in /trajectory/%s/%d",
                surface.label, len(self.vertices), len(self.shown), FRAME_VERTICES,
                GROUP, surface.index, GROUP, surface.index,
            )  # fmt: skip

    def grid(self) -> ObstacleGrid:
        s = self.surface
        shown = self.shown_triangles
        count = len(self.shown)
        return ObstacleGrid(s.index, s.kind, self.moving, count, len(shown), self.simplified)

    @property
    def origin(self) -> np.ndarray:
        return self.body.center if self.body is not None else self.surface.motion.origin

    def state(self, frame: dict) -> tuple[np.ndarray, np.ndarray]:
        """A free body's (velocity, angular velocity) in a frame (x, v)."""
        v = frame.get("v")
        if v is None:
            return np.zeros(3), np.zeros(3)
        return self.body.frame.motion(frame["x"], v)

    def pose(self, t: float, frame: dict | None = None):
        """(center, rotation, shown vertices) at time t (a free body: in ``frame``)."""
        if self.body is not None:
            assert frame is not None, "a free body's pose is in its frame (x, v)"
            c, R = self.body.frame.pose(frame["x"])
            return c, R, c + (self.shown - self.body.center) @ R.T
        motion = self.surface.motion
        c, R = motion.pose(t)
        return c, R, motion.place(self.shown, t, (c, R))


class Obstacles:
    """The obstacles of a scene as a ``ResultWriter`` stores them (none without a case or
    obstacles): ``write_mesh``, ``create_trajectory``, ``append``, ``write_result`` and
    ``grids`` (for the sidecar)."""

    def __init__(self, scene: Scene):
        obstacles = scene.case.obstacles if scene.case is not None else ()
        self.items = []
        self.moving = []
        if not obstacles:
            return
        from catenet.output.surfaces import surface

        net = scene.net
        cover = net.nodes[: net.n_net]
        cap = frame_cap(net.n_nodes)
        free = {b.obstacle: b for b in scene.rigid}
        for k, obs in enumerate(obstacles):
            s = surface(obs.to_dict(), k, cover)
            if s is not None:
                self.items.append(_Item(s, cap, free.get(k)))
        self.moving = [item for item in self.items if item.moving]

    def __len__(self) -> int:
        return len(self.items)

    def grids(self) -> list[ObstacleGrid]:
        return [item.grid() for item in self.items]

    def write_mesh(self, mesh) -> None:
        """/mesh/obstacles (nothing without obstacles)."""
        if not self.items:
            return
        group = mesh.create_group(GROUP)
        group.attrs["count"] = len(self.items)
        for item in self.items:
            s = item.surface
            g = group.create_group(str(s.index))
            g.attrs["kind"] = s.kind
            g.attrs["obstacle"] = s.index
            g.attrs["moving"] = item.moving
            g.create_dataset("vertices", data=item.vertices)
            g.create_dataset("triangles", data=item.triangles)
            if item.moving:
                g.attrs["origin"] = item.origin
            if item.body is not None:
                g.attrs["free"] = True
                g.attrs["mass"] = item.body.mass
                g.create_dataset("inertia", data=np.asarray(item.body.inertia, dtype=np.float64))
                g.create_dataset("axes", data=np.asarray(item.body.axes, dtype=np.float64))
            if item.simplified:
                g.create_dataset("frame_triangles", data=item.shown_triangles)

    def create_trajectory(self, traj) -> None:
        """The moving obstacles' per-frame datasets in /trajectory, empty."""
        for item in self.moving:
            g = traj.create_group(f"{GROUP}/{item.surface.index}")
            nv = len(item.shown)
            sets = [
                ("center", (3,), (POSE_CHUNK, 3), False),
                ("rotation", (3, 3), (POSE_CHUNK, 3, 3), False),
                ("vertices", (nv, 3), (1, nv, 3), True),
            ]
            if item.body is not None:
                sets += [(n, (3,), (POSE_CHUNK, 3), False) for n in FREE_SETS]
            for name, tail, chunks, gzip in sets:
                extra = {"compression": "gzip", "compression_opts": 4, "shuffle": True}
                g.create_dataset(
                    name,
                    shape=(0, *tail),
                    maxshape=(None, *tail),
                    dtype="f8",
                    chunks=chunks,
                    fillvalue=np.nan,
                    **(extra if gzip else {}),
                )

    def append(self, traj, times, n0: int, held: list, frames=None) -> None:
        """Writes the moving obstacles' frames n0, n0 + 1, ... (at ``times``; ``frames``:
        each one's data, x and v, for the free bodies); ``held`` keeps the datasets open
        as long as the file (``catenet.output.writer``)."""
        n1 = n0 + len(times)
        frames = frames if frames is not None else [{}] * len(times)
        for item in self.moving:
            g = traj[f"{GROUP}/{item.surface.index}"]
            names: tuple[str, ...] = ("center", "rotation", "vertices")
            names += FREE_SETS if item.body is not None else ()
            sets = [g[name] for name in names]
            held.extend(sets)
            for ds in sets:
                ds.resize(n1, axis=0)
            poses = [item.pose(t, f) for t, f in zip(times, frames, strict=True)]
            sets[0][n0:n1] = np.array([c for c, _, _ in poses])
            sets[1][n0:n1] = np.array([R for _, R, _ in poses])
            sets[2][n0:n1] = np.array([V for _, _, V in poses])  # one write: a chunk a frame
            if item.body is not None:
                motion = [item.state(f) for f in frames]
                sets[3][n0:n1] = np.array([v for v, _ in motion])
                sets[4][n0:n1] = np.array([w for _, w in motion])

    def write_result(self, result, t: float, res: Result | None = None) -> None:
        """/result/obstacles: the moving obstacles at the final time t (the free bodies
        in the result ``res``'s state)."""
        if not self.moving or not math.isfinite(t):
            return
        frame = {} if res is None else {"x": res.x, "v": res.v}
        for item in self.moving:
            if item.body is not None and res is None:
                continue
            g = result.create_group(f"{GROUP}/{item.surface.index}")
            c, R, V = item.pose(t, frame)
            g.create_dataset("center", data=c)
            g.create_dataset("rotation", data=R)
            g.create_dataset("vertices", data=V)
            if item.body is not None:
                v, w = item.state(frame)
                g.create_dataset("velocity", data=v)
                g.create_dataset("angular_velocity", data=w)


# --------------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------------


def grids(h5) -> list[ObstacleGrid]:
    """What the sidecar shows of the obstacles of an open result file."""
    group = h5.get(f"mesh/{GROUP}")
    if group is None:
        return []
    out = []
    for key in sorted(group, key=int):
        g = group[key]
        simplified = "frame_triangles" in g
        tri = g["frame_triangles" if simplified else "triangles"]
        moving = bool(g.attrs.get("moving", False))
        traj = h5.get(f"trajectory/{GROUP}/{key}/vertices")
        nv = traj.shape[1] if moving and traj is not None else len(g["vertices"])
        kind = read_text(g.attrs.get("kind", ""))
        out.append(ObstacleGrid(int(key), kind, moving, nv, len(tri), simplified))
    return out


@dataclass(frozen=True)
class StoredObstacle:
    """Obstacle ``index`` of a result file (see the module docstring): its surface at
    t = 0 (``vertices``, ``triangles``), and for a moving one (``origin``) the frames'
    ``times``, ``center`` (F, 3), ``rotation`` (F, 3, 3) and surface ``frames`` (F, V', 3)
    with its ``frame_triangles``, and ``final`` (V', 3) at /result's time (None: not
    written)."""

    index: int
    kind: str
    moving: bool
    vertices: np.ndarray
    triangles: np.ndarray
    origin: np.ndarray | None = None
    times: np.ndarray | None = None
    center: np.ndarray | None = None
    rotation: np.ndarray | None = None
    frames: np.ndarray | None = None
    frame_triangles: np.ndarray | None = None
    final: np.ndarray | None = None

    @property
    def label(self) -> str:
        return f"obstacle[{self.index}]: {'moving ' if self.moving else ''}{self.kind}"


def read_obstacles(path: str | Path) -> list[StoredObstacle]:
    """The obstacles of a result file (empty without any), each with its complete frames
    (those of the net: ``trajectory_length``)."""

    out = []
    with open_result(path) as h5:
        n = trajectory_length(h5)
        times = np.asarray(h5["trajectory/time"][:n]) if n else np.zeros(0)
        for grid in grids(h5):
            g = h5[f"mesh/{GROUP}/{grid.index}"]
            V, T = np.asarray(g["vertices"]), np.asarray(g["triangles"])
            if not grid.moving:
                out.append(StoredObstacle(grid.index, grid.kind, False, V, T))
                continue
            stored = h5.get(f"trajectory/{GROUP}/{grid.index}")
            per_frame = {
                name: np.asarray(stored[name][:n]) if stored is not None else None
                for name in ("center", "rotation", "vertices")
            }
            final = h5.get(f"result/{GROUP}/{grid.index}/vertices")
            out.append(
                StoredObstacle(
                    grid.index,
                    grid.kind,
                    True,
                    V,
                    T,
                    origin=np.asarray(g.attrs["origin"], dtype=np.float64),
                    times=times if stored is not None else np.zeros(0),
                    center=per_frame["center"],
                    rotation=per_frame["rotation"],
                    frames=per_frame["vertices"],
                    frame_triangles=np.asarray(h5[grid.topology]),
                    final=None if final is None else np.asarray(final),
                )
            )
    return out
