"""Contact along the whole edge (``solver.edge_contact``), for the scene builder: which
edges are capsules, their barrier against an obstacle's, a ball's or a free body's
outline (``catenet.terms.segments.EdgeContact``) and the start check that no edge
passes through a solid.

The node barriers of the same solids are grown by the contact radius r where they are
built (``catenet.scene.contact``, ``catenet.scene.bodies``, ``catenet.scene.rigid``);
a plane needs no more (a segment cannot cross a plane without an end crossing it)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from catenet.errors import ConfigError

if TYPE_CHECKING:
    from catenet.model.net import Net
    from catenet.scene.contact import Shown
    from catenet.scene.shapes import Shape
    from catenet.terms.segments import EdgeContact


def contact_edges(net: Net) -> np.ndarray:
    """The net's edges (K, 2) with at least one free node: the capsules."""
    edges = net.edges[: net.n_edges]
    free = ~net.fixed
    return np.ascontiguousarray(edges[free[edges[:, 0]] | free[edges[:, 1]]], dtype=np.int64)


def held_edges(net: Net) -> np.ndarray:
    """The net's edges (K, 2) with both nodes fixed: no barrier moves them, a moving
    obstacle must not run over them."""
    edges = net.edges[: net.n_edges]
    held = net.fixed[edges[:, 0]] & net.fixed[edges[:, 1]]
    return np.ascontiguousarray(edges[held], dtype=np.int64)


def edge_barrier(
    shape: Shape,
    net: Net,
    r: float,
    kappa: float,
    dhat: float,
    weights: ArrayLike | None = None,
    bnodes: ArrayLike | None = None,
    edges: np.ndarray | None = None,
) -> EdgeContact | None:
    """The barrier of the net's capsules of radius r against ``shape``'s outline, its
    points riding on ``bnodes`` by ``weights`` (a ball's, a body's; None: fixed); None
    for a plane (the nodes' barrier holds a segment off it). ``edges``: these (K, 2)
    instead of ``contact_edges``."""
    from catenet.terms.segments import EdgeContact

    if shape.kind == "plane":
        return None
    points, lines, radius = edge_outline(shape)
    edges = contact_edges(net) if edges is None else edges
    rest = np.linalg.norm(net.nodes[edges[:, 1]] - net.nodes[edges[:, 0]], axis=1)
    return EdgeContact(
        edges, rest, points, lines, radius, r=r, kappa=kappa, dhat=dhat,
        n_nodes=net.n_nodes, weights=weights, bnodes=bnodes,
    )  # fmt: skip


def edge_outline(shape: Shape) -> tuple[np.ndarray, np.ndarray, float | np.ndarray]:
    """The outline the net's edges meet: the shape's own ``edge_outline`` where it has one
    (a cylinder's exact core and end bands: on its prisms alone a frictionless rope
    wrapped half round it lost a quarter of its tension at their corners), else its
    ``outline``. Points, lines and their radius (one, or one per line)."""
    own = getattr(shape, "edge_outline", None)
    if own is not None:
        out: tuple[np.ndarray, np.ndarray, float | np.ndarray] = own()
        return out
    points, lines, radius = shape.outline()
    return points, lines, radius


def check_edges_clear(
    label: str, shape: Shape, r: float, dhat: float, net: Net, shown: Shown
) -> None:
    """ConfigError where an edge of the net starts inside or on ``shape`` grown by r:
    the exact first contact of each segment, walked from one end to the other, with
    the shape (its nodes are checked by the node barrier's own check)."""
    edges = contact_edges(net)
    if not len(edges) or shape.kind == "plane":
        return
    start = np.ascontiguousarray(net.nodes[edges[:, 0]])
    along = np.ascontiguousarray(net.nodes[edges[:, 1]] - start)
    probe = shape.barrier(np.arange(len(edges)), 1.0, dhat, offset=r)
    if not probe.first_hit(start, along, 0.0, 1.0) <= 1.0:
        return
    one = shape.barrier(np.zeros(1, dtype=np.int64), 1.0, dhat, offset=r)
    for k, (i, j) in enumerate(edges.tolist()):  # the first edge that does, for the message
        if one.first_hit(start[k : k + 1], along[k : k + 1], 0.0, 1.0) <= 1.0:
            raise ConfigError(
                f"{label}: the edge {i}-{j} from {shown(net.nodes[i].tolist())} to "
                f"{shown(net.nodes[j].tolist())} passes through it or within the contact "
                f"radius {r:.3g} m of it at the start: an obstacle must not overlap the "
                "initial net; move it or the net"
            )


def check_outline_clear(label: str, edge: EdgeContact, r: float, net: Net, shown: Shown) -> None:
    """ConfigError where an edge of the net starts within r of the solid's outline though
    clear of the solid (``check_edges_clear``): a cylinder's circumscribed prisms (its end
    bands', ``edge_outline``) stand up to 0.5 % of its radius beyond its round side, and
    a rope given 2.5 mm off a cylinder with a 2 mm contact radius started 1.98 mm from a
    prism's corner, where its barrier is infinite: the run stagnated, blaming Newton."""
    gaps = edge.gap(net.nodes)
    if not gaps.size or gaps.min() > 0.0:
        return
    k = int(np.argmin(gaps))
    i, j = (int(n) for n in edge.edges[k])
    raise ConfigError(
        f"{label}: the edge {i}-{j} from {shown(net.nodes[i].tolist())} to "
        f"{shown(net.nodes[j].tolist())} passes within the contact radius {r:.3g} m of its "
        "outline at the start (near a cylinder's ends the edges meet circumscribed prisms "
        "of 32 sides, up to 0.5 % of its radius beyond its round side: "
        "docs/guide/edge-contact.md): an obstacle must not overlap the initial net; move "
        "it or the net"
    )
