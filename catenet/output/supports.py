"""Rollers, sliders and elastic supports in a result file (``catenet.model.guides``):
which nodes they hold and how. Fixed nodes are ``/mesh/fixed``; the group
``/mesh/supports`` is written only for a net with the others:

```
/mesh/supports/roller_nodes      (R,) int64
/mesh/supports/roller_normal     (R, 3) float64   unit normal (the held direction)
/mesh/supports/slider_nodes      (S,) int64
/mesh/supports/slider_direction  (S, 3) float64   unit direction (the free one)
/mesh/supports/spring_nodes      (K,) int64       (a node with several springs: each)
/mesh/supports/spring_stiffness  (K, 3, 3) float64 [N/m], toward the node's /mesh/nodes
/mesh/supports/end_spring_nodes      (E,) int64   rod ends on a 6x6 spring (summed per node)
/mesh/supports/end_spring_other      (E,) int64   the other node of each one's end edge
/mesh/supports/end_spring_stiffness  (E, 6, 6) float64 the 6x6 as given (x, y, z, rx, ry, rz)
```

Their reactions are in ``/result/reaction`` with the fixed nodes', a rod end's moment
in ``/result/reaction_moment``.
"""

from __future__ import annotations

import numpy as np


def write_supports(mesh, net) -> None:
    """Adds /mesh/supports for the net's rollers, sliders and springs (none: nothing)."""
    guides, springs = net.guides, net.springs
    if guides is None and springs is None:
        return
    g = mesh.create_group("supports")
    if guides is not None:
        for name, axis, count in (("roller", "normal", 2), ("slider", "direction", 1)):
            mine = guides.free_count == count
            g.create_dataset(f"{name}_nodes", data=guides.nodes[mine].astype(np.int64))
            g.create_dataset(f"{name}_{axis}", data=guides.axis[mine].astype(np.float64))
    if springs is not None and springs.nodes.size:
        g.create_dataset("spring_nodes", data=springs.nodes.astype(np.int64))
        g.create_dataset("spring_stiffness", data=springs.stiffness.astype(np.float64))
    ends = None if springs is None else springs.ends
    if ends is not None:
        g.create_dataset("end_spring_nodes", data=ends.nodes.astype(np.int64))
        g.create_dataset("end_spring_other", data=ends.other.astype(np.int64))
        g.create_dataset("end_spring_stiffness", data=ends.stiffness.astype(np.float64))


def read_supported(path, n_nodes: int) -> np.ndarray | None:
    """(N,) bool: the nodes on rollers, sliders and springs of a result file (None: none,
    or a file that cannot tell)."""
    from catenet.output.reader import DAMAGED, open_result

    try:
        with open_result(path) as h5:
            group = h5.get("mesh/supports")
            if group is None:
                return None
            nodes = [np.asarray(group[k]) for k in group if k.endswith("_nodes")]
    except DAMAGED:
        return None
    mask = np.zeros(n_nodes, bool)
    for part in nodes:
        part = part[(part >= 0) & (part < n_nodes)]
        mask[part.astype(np.int64)] = True
    return mask if mask.any() else None
