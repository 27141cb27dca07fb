"""Point masses and initial velocities of a case (``[[mass]]``): the corner masses of a
tether net, thrown with a velocity.

Each table puts ``mass`` [kg] at a node (or at each node of a node set), where it adds
to the lumped mass of the cables (inertia, and weight under ``load.gravity``), and gives
the node an initial ``velocity`` in dynamic runs. A table may give a velocity alone
(``mass = 0``, the default): an initial velocity of that node.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from catenet.case.keys import BAD, Checker, Context, Declared, node, parse_table, real, show, vec3
from catenet.case.kinds.base import expand
from catenet.errors import ConfigError


@dataclass(frozen=True)
class MassConfig(Declared):
    """A point mass and/or an initial velocity at a node (each node of a node set)."""

    node: Any = node(missing="the node that carries the mass", doc="the node, or a node set")
    mass: float = real(0.0, ge=0, unit="kg", doc="point mass added to the node's lumped mass")
    velocity: tuple | None = vec3(
        None,
        write="given",
        shown="none",
        unit="m/s",
        doc="dynamic: initial velocity [vx, vy, vz] of the node (free nodes only)",
    )


def parse_masses(ck: Checker, value: Any, ctx: Context) -> tuple | Any:
    """The ``[[mass]]`` array of tables (absent: none)."""
    if value is None:
        return ()
    out = []
    for k, t in enumerate(ck.array_of_tables(value, "mass")):
        path = f"mass[{k}]"
        m = parse_table(ck, t, MassConfig, path, ctx)
        if m is not BAD and m.mass == 0.0 and m.velocity is None:
            ck.add(f"{path}: gives neither mass > 0 nor velocity: give at least one of them")
            m = BAD
        out.append(m)
    return BAD if BAD in out else tuple(out)


def point_masses(masses, net, names, sets) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The point masses (N,) [kg] and initial velocities (N, 3) [m/s] of ``[[mass]]``
    (None where no table gives any). Raises ConfigError with the key path for a node out
    of range, a velocity on a fixed node or two velocities for one node."""
    if not masses:
        return None, None
    n = net.n_nodes
    pm = np.zeros(n)
    v = np.zeros((n, 3))
    given: dict[int, int] = {}
    for k, m in enumerate(masses):
        path = f"mass[{k}].node"
        try:
            nodes = expand(m.node, names, sets)
        except KeyError:
            raise ConfigError(
                f"{path} = {show(m.node)}: is neither a node name nor a node set of the net"
            ) from None
        for i in nodes:
            if not 0 <= i < n:
                raise ConfigError(f"{path} = {show(m.node)}: must be a node index in 0..{n - 1}")
            pm[i] += m.mass
            if m.velocity is None:
                continue
            if net.fixed[i]:
                raise ConfigError(
                    f"mass[{k}].velocity = {list(m.velocity)}: node {i} is fixed: only free "
                    "nodes start with a velocity"
                )
            if i in given and not np.array_equal(v[i], m.velocity):
                raise ConfigError(
                    f"mass[{k}].velocity = {list(m.velocity)}: node {i} already has "
                    f"mass[{given[i]}].velocity = {v[i].tolist()}: one velocity per node"
                )
            given[i] = k
            v[i] = m.velocity
    return (pm if pm.any() else None), (v if given else None)
