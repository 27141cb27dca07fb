"""The /result group of a result file (contract §5 and §7): the final state, its
tensions (per cable too: ``cable_max_tension``, ..., and with the run's peaks
``cable_peak_tension`` and ``cable_peak_tension_time``), reactions and contact forces,
the run's peaks over every step (``peak_tension``, ``peak_tension_time``,
``least_tension``, ``peak_displacement``, ``peak_displacement_time``), a case with rods'
``bending_moment`` and ``curvature`` per node (``twisting_moment`` per edge where they
twist; ``reaction_moment`` per node, 0 but where a support holds a rod end's direction: a
clamp, a rotational or a 6x6 spring), velocities and the newmark scheme's acceleration
where the run keeps them, each
edge's ``utilisation`` (and ``peak_utilisation`` from its peak tension; per cable
``cable_max_utilisation``; NaN where no breaking load is given: ``catenet.model.design``)
and the attributes a user reads first (``catenet.model.summary``)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from catenet.model import summary
from catenet.output.metadata import result_attrs

if TYPE_CHECKING:
    from catenet.scene.scene import Scene
    from catenet.solver.result import Result

PEAKS = (
    "peak_tension",
    "peak_tension_time",
    "least_tension",
    "peak_displacement",
    "peak_displacement_time",
)


def write_result_group(
    h5,
    scene: Scene,
    res: Result,
    tension: np.ndarray,
    attrs: dict,
    velocities: bool,
    accelerations: bool,
    name: str = "result",
):
    """Writes /result (or the group ``name`` in its layout, e.g. a load case's
    cases/<name>; replacing one there) for the Result ``res`` of ``scene`` with the
    stored ``tension``; ``attrs`` add to its attributes. Returns the group."""
    if name in h5:
        del h5[name]
    g = h5.create_group(name)
    g.create_dataset("x", data=np.asarray(res.x, dtype=np.float64))
    g.create_dataset("tension", data=tension)
    cables = scene.cables
    peaks = res.peaks
    use = utilisation(scene, tension)
    g.create_dataset("utilisation", data=use)
    if peaks is not None and np.isfinite(use).any():
        top = np.nan_to_num(np.asarray(peaks.arrays()["peak_tension"]), nan=0.0)
        g.create_dataset("peak_utilisation", data=utilisation(scene, top))
    if cables is not None:
        per = summary.cable_summary(
            scene.net, res.x, tension, cables.edge, cables.names, peaks=peaks, utilisation=use
        )
        keys = [
            ("max_tension", np.float64),
            ("slack_fraction", np.float64),
            ("max_compression", np.float64),
            ("slack_edges", np.int64),
            ("max_utilisation", np.float64),
        ]
        if peaks is not None:
            keys += [("peak_tension", np.float64), ("peak_tension_time", np.float64)]
        for key, dtype in keys:
            g.create_dataset(f"cable_{key}", data=np.array([c[key] for c in per.values()], dtype))
    if peaks is not None:
        for key, value in peaks.arrays().items():
            g.create_dataset(key, data=value)
    bent = summary.bending_moments(scene, res.x)
    if bent is not None:  # per node [N m] and [1/m], 0 where nothing bends
        moment, kappa = bent
        g.create_dataset("bending_moment", data=moment)
        g.create_dataset("curvature", data=kappa)
    twisting = summary.twisting_moments(scene, res.x)
    if twisting is not None:  # per edge [N m], 0 where no rod twists
        g.create_dataset("twisting_moment", data=twisting)
    reaction = res.reaction if res.reaction is not None else np.zeros_like(res.x)
    g.create_dataset("reaction", data=np.asarray(reaction, dtype=np.float64))
    moments = summary.support_moments(scene, res.x)
    if moments is None and bent is not None:  # rods, no end held in direction: all 0
        moments = np.zeros_like(res.x)
    if moments is not None:  # at rod ends held in direction, 0 elsewhere [N m]
        g.create_dataset("reaction_moment", data=moments)
    if scene.design is not None and scene.design.anchored:  # |R| / capacity per node
        g.create_dataset("support_utilisation", data=scene.design.support_utilisation(reaction))
    contact = res.contact_force
    if contact is None or not np.all(np.isfinite(contact)):
        contact = np.zeros_like(res.x)
    g.create_dataset("contact_force", data=np.asarray(contact, dtype=np.float64))
    v = res.v
    if velocities and v is not None and np.all(np.isfinite(v)):
        g.create_dataset("v", data=np.asarray(v, dtype=np.float64))
    a = res.a
    if accelerations and a is not None and np.all(np.isfinite(a)):
        g.create_dataset("a", data=np.asarray(a, dtype=np.float64))
    for key, value in {**result_attrs(res, scene, tension), **attrs}.items():
        g.attrs[key] = value
    return g


def utilisation(scene: Scene, tension: np.ndarray) -> np.ndarray:
    """Each edge's utilisation (design tension / design resistance, ``scene.design``) of
    the tensions ``tension`` (M,); NaN where no breaking load is given (every edge of a
    scene without design data)."""
    design = scene.design
    if design is None:
        return np.full(len(tension), np.nan)
    return np.asarray(design.utilisation(tension), dtype=np.float64)
