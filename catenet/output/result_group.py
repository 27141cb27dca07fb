"""The /result group of a result file (contract §5 and §7): the final state, its
tensions (per cable too), reactions and contact forces, velocities and the newmark
scheme's acceleration where the run keeps them, and the attributes a user reads first."""

from __future__ import annotations

import numpy as np

from catenet.model import measures
from catenet.output.metadata import result_attrs


def write_result_group(h5, scene, res, tension, attrs: dict, velocities: bool, accelerations: bool):
    """Writes /result (replacing one there) for the Result ``res`` of ``scene`` with the
    stored ``tension``; ``attrs`` add to its attributes. Returns the group."""
    if "result" in h5:
        del h5["result"]
    g = h5.create_group("result")
    g.create_dataset("x", data=np.asarray(res.x, dtype=np.float64))
    g.create_dataset("tension", data=tension)
    cables = getattr(scene, "cables", None)
    if cables is not None:
        top, slack = measures.cable_stats(scene.net, res.x, tension, cables.edge, len(cables.names))
        g.create_dataset("cable_max_tension", data=top)
        g.create_dataset("cable_slack_fraction", data=slack)
    reaction = res.reaction if res.reaction is not None else np.zeros_like(res.x)
    g.create_dataset("reaction", data=np.asarray(reaction, dtype=np.float64))
    contact = getattr(res, "contact_force", None)
    if contact is None or not np.all(np.isfinite(contact)):
        contact = np.zeros_like(res.x)
    g.create_dataset("contact_force", data=np.asarray(contact, dtype=np.float64))
    v = getattr(res, "v", None)
    if velocities and v is not None and np.all(np.isfinite(v)):
        g.create_dataset("v", data=np.asarray(v, dtype=np.float64))
    a = getattr(res, "a", None)
    if accelerations and a is not None and np.all(np.isfinite(a)):
        g.create_dataset("a", data=np.asarray(a, dtype=np.float64))
    for key, value in {**result_attrs(res, scene), **attrs}.items():
        g.attrs[key] = value
    return g
