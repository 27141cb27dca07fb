"""What names the parts of a net in a result file: the cable of every edge
(``/mesh/cable`` with the attribute ``cable_names``) and the case's node sets
(``/mesh/sets/<name>``: node indices, e.g. a set of supports), for reports by name."""

from __future__ import annotations

import numpy as np


def write_net_index(mesh, scene) -> None:
    """Writes a scene's cables and node sets into the /mesh group ``mesh``."""
    import h5py

    cables = scene.cables
    if cables is not None:  # a graph's cables: the cable of every edge (-1: none)
        mesh.create_dataset("cable", data=np.asarray(cables.edge, dtype=np.int64))
        mesh.attrs["cable_names"] = np.array(cables.names, dtype=h5py.string_dtype())
    named = {k: v for k, v in (scene.sets or {}).items() if not str(k).startswith("cable:")}
    if named:
        group = mesh.create_group("sets")
        for name, nodes in named.items():
            group.create_dataset(str(name), data=np.asarray(nodes, dtype=np.int64))


def read_sets(mesh) -> dict[str, np.ndarray]:
    """The node sets of an open /mesh group ({} where the file keeps none)."""
    group = mesh.get("sets")
    if group is None:
        return {}
    return {str(k): np.asarray(v, dtype=np.int64).reshape(-1) for k, v in group.items()}
