"""Naming what makes a stiffness matrix singular or indefinite: the nodes of a mechanism.

A node's own 3x3 block of the edges' tangent stiffness, sum over its edges of
(EA/l0) w'' t t^T + (N/|e|)(I - t t^T), is its stiffness when its neighbours stay put.
Where that block has a negative eigenvalue the whole matrix is indefinite (its Rayleigh
quotient along that node's direction is negative): the node is pushed sideways by
compressed bilateral edges more than anything holds it (a joint in a chain of struts, a
straight compressed strut's interior). Such nodes are named in the messages of an
unstable equilibrium, with the edges (and cables) in compression that meet there.
"""

from __future__ import annotations

import numpy as np

NEGATIVE = 1e-9  # a block eigenvalue below -NEGATIVE x the block's largest is negative


def unstable_nodes(stretch, x: np.ndarray, free: np.ndarray) -> np.ndarray:
    """Free nodes whose own block of the edges' tangent stiffness at x (N, 3) has a
    negative eigenvalue (``stretch``: the net's ``terms.Stretch``; ``free`` (N,) bool)."""
    net = stretch.net
    values = np.empty(36 * net.n_edges)
    stretch.hessian(x, values)
    h = values.reshape(-1, 6, 6)
    blocks = np.zeros((net.n_nodes, 3, 3))
    np.add.at(blocks, net.edges[:, 0], h[:, :3, :3])
    np.add.at(blocks, net.edges[:, 1], h[:, 3:, 3:])
    eig = np.linalg.eigvalsh(blocks)
    size = np.max(np.abs(eig), axis=1)
    return np.flatnonzero(free & (eig[:, 0] < -NEGATIVE * size))


def compressed_edges(stretch, x: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """Bilateral edges in compression at x that meet one of ``nodes``."""
    net = stretch.net
    at = np.isin(net.edges, nodes).any(axis=1)
    return np.flatnonzero(at & (stretch.tension(x) < 0.0))


def describe_unstable(
    stretch, x: np.ndarray, free: np.ndarray, cable_names=None, cable_of_edge=None
) -> str:
    """One sentence naming the nodes (and cables) of an unstable equilibrium and the fix."""
    nodes = unstable_nodes(stretch, x, free)
    if nodes.size == 0:  # a global instability: name the compressed edges' free nodes
        compressed = np.flatnonzero(stretch.tension(x) < 0.0)
        nodes = np.unique(stretch.net.edges[compressed])
        nodes = nodes[free[nodes]]
    edges = compressed_edges(stretch, x, nodes)
    shown = ", ".join(map(str, nodes[:10])) + (
        f" and {nodes.size - 10} more" if nodes.size > 10 else ""
    )
    where = f"nodes {shown}" if nodes.size else "the net"
    cables = ""
    if cable_names is not None and cable_of_edge is not None and edges.size:
        names = sorted({str(cable_names[c]) for c in cable_of_edge[edges] if c >= 0})
        if names:
            cables = f" (cables {', '.join(names)})"
    return (
        f"a mechanism: the stiffness is negative at {where}, where compressed bilateral "
        f"edges{cables} push the net sideways more than anything holds it (a chain of "
        "pinned struts, a straight compressed strut): fix or brace those nodes (a support, "
        "an edge to a support, guys with prestress), or make the strut one edge"
    )
