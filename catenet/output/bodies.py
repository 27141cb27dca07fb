"""Moving spheres in a result file: where their centres are and what they are.

A rigid ball or a ball on a prescribed path (``catenet.scene.bodies``) is a node of the
net, after all of the net's own nodes, so its centre's trajectory is part of
``/trajectory/x`` and its final place part of ``/result/x``. The group ``/mesh/bodies``
says which nodes they are:

```
/mesh/bodies/node        (B,) int64   the centre's node index (rows of x, v)
/mesh/bodies/obstacle    (B,) int64   its [[obstacle]] table
/mesh/bodies/radius      (B,) float64 [m]
/mesh/bodies/mass        (B,) float64 [kg] (a path's ball: the net's mass, nominal)
/mesh/bodies/prescribed  (B,) bool    on a prescribed path (else a free rigid body)
/mesh/bodies             attrs: count
```

``read_bodies(path)`` gives them back with the centres' trajectory (``times``,
``center`` (F, B, 3), ``velocity`` (F, B, 3) when stored) and final place.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from catenet.output.reader import open_result, trajectory_length


def write_bodies(mesh, scene) -> None:
    """Adds /mesh/bodies for the scene's moving spheres (nothing without any)."""
    bodies = scene.bodies
    if not bodies:
        return
    g = mesh.create_group("bodies")
    g.attrs["count"] = len(bodies)
    g.create_dataset("node", data=np.array([b.node for b in bodies], dtype=np.int64))
    g.create_dataset("obstacle", data=np.array([b.obstacle for b in bodies], dtype=np.int64))
    g.create_dataset("radius", data=np.array([b.radius for b in bodies], dtype=np.float64))
    g.create_dataset("mass", data=np.array([b.mass for b in bodies], dtype=np.float64))
    g.create_dataset("prescribed", data=np.array([b.prescribed for b in bodies], dtype=bool))


@dataclass(frozen=True)
class Bodies:
    """The moving spheres of a result file (B of them; see the module docstring)."""

    node: np.ndarray
    obstacle: np.ndarray
    radius: np.ndarray
    mass: np.ndarray
    prescribed: np.ndarray
    times: np.ndarray  # (F,) the trajectory's frames (empty: none written)
    center: np.ndarray  # (F, B, 3)
    velocity: np.ndarray | None  # (F, B, 3), when the trajectory has velocities
    final: np.ndarray | None  # (B, 3) from /result/x (None: the run wrote no result)

    def __len__(self) -> int:
        return len(self.node)


def body_nodes(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """The centres' node indices (B,) and radii (B,) of a result file's moving spheres
    (empty without any), without their trajectory."""

    with open_result(path) as h5:
        g = h5.get("mesh/bodies")
        if g is None:
            return np.zeros(0, dtype=np.int64), np.zeros(0)
        return np.asarray(g["node"], dtype=np.int64), np.asarray(g["radius"], dtype=np.float64)


def read_bodies(path: str | Path) -> Bodies:
    """The moving spheres of a result file and their centres' trajectory (none: B = 0)."""

    with open_result(path) as h5:
        g = h5.get("mesh/bodies")
        if g is None:
            z = np.zeros(0)
            return Bodies(
                z.astype(np.int64), z.astype(np.int64), z, z, z.astype(bool), z,
                np.zeros((0, 0, 3)), None, None,
            )  # fmt: skip
        node = np.asarray(g["node"], dtype=np.int64)
        traj = h5.get("trajectory")
        n = trajectory_length(h5) if traj is not None else 0
        times = np.asarray(traj["time"][:n]) if n else np.zeros(0)
        center = np.asarray(traj["x"][:n])[:, node] if n else np.zeros((0, len(node), 3))
        velocity = np.asarray(traj["v"][:n])[:, node] if n and "v" in traj else None
        final = np.asarray(h5["result/x"])[node] if "result/x" in h5 else None
        return Bodies(
            node,
            np.asarray(g["obstacle"], dtype=np.int64),
            np.asarray(g["radius"], dtype=np.float64),
            np.asarray(g["mass"], dtype=np.float64),
            np.asarray(g["prescribed"], dtype=bool),
            times,
            center,
            velocity,
            final,
        )
