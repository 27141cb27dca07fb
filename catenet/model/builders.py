"""Builders of nets: a single cable, the paper's square net, an explicit graph."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from catenet.errors import ConfigError
from catenet.model.laws import Law, prestressed_lengths, table_rows
from catenet.model.limits import carried, too_large
from catenet.model.memory import fits
from catenet.model.net import Net

#: The largest net the builders make (the case loader also checks memory beforehand).
MAX_NODES = 50_000_000
WITHIN = f"within {too_large()}"


def _check_size(nodes: float, edges: float, where: str) -> None:
    """ConfigError for a net of more than MAX_NODES nodes or one whose solve could not fit
    in this machine's memory at all (the case loader asks for a margin beforehand)."""
    if not nodes <= MAX_NODES:
        raise ConfigError(
            f"{where}: the net could have about {nodes:.2g} nodes; catenet builds at most "
            f"{MAX_NODES:.0e}"
        )
    ok, need, total = fits(nodes, edges)
    if not ok and total is not None:  # (not ok: the machine's memory is known)
        raise ConfigError(
            f"{where}: the net could have about {nodes:.2g} nodes and its solve need about "
            f"{need / 2**30:.2g} GiB; this machine has {total / 2**30:.0f} GiB"
        )


@dataclass(frozen=True)
class Material:
    """What the edges of a net are made of: axial stiffness EA [N] (every law's
    small-strain stiffness), mass per length rho*A [kg/m], the tension-only switch, the
    material law (a name in ``catenet.model.laws.LAWS``; ``table``: the (strain, tension)
    points of the "table" law) and ``prestress``, the tension [N] every edge carries in the
    given geometry (None: the rest lengths are the builder's). Every builder makes its
    net under it, once (``net``)."""

    EA: float
    line_density: float = 0.0
    tension_only: bool = True
    law: str = "linear"
    table: tuple | None = None
    prestress: float | None = None

    @classmethod
    def from_E(cls, E: float, *, radius=None, area=None, density=0.0, **law) -> Material:
        """From Young's modulus and a circular radius (A = pi r^2) or an area; ``law``:
        tension_only, law, table, prestress."""
        if (radius is None) == (area is None):
            raise ConfigError("material: give exactly one of radius and area")
        A = math.pi * radius**2 if area is None else area
        return cls(EA=E * A, line_density=density * A, **law)

    def law_of(self, n_edges: int, tension_only=None) -> Law:
        """The law of ``n_edges`` edges of this material (``tension_only``: one switch per
        edge instead of the material's)."""
        rows = table_rows(self.table)[0] if self.law == "table" else None
        only = self.tension_only if tension_only is None else tension_only
        return Law.uniform(n_edges, self.law, tension_only=only, table=rows)

    def net(self, nodes, edges, *, fixed, EA=None, rest_length=None, flies=False) -> Net:
        """The net of these nodes and edges under this material: its law on every edge
        and, with a prestress, the rest lengths at which every edge carries it in the
        given geometry (else ``rest_length``, default the edges' lengths); ``EA`` per edge
        overrides the material's; ``flies``: parts of it may have no support (dynamic
        runs)."""
        return self.prestressed(
            self.unstressed(nodes, edges, fixed=fixed, EA=EA, rest_length=rest_length, flies=flies)
        )

    def unstressed(self, nodes, edges, *, fixed, EA=None, rest_length=None, flies=False) -> Net:
        """``net`` without the prestress: the rest lengths as given."""
        return Net.from_arrays(
            nodes,
            edges,
            EA=self.EA if EA is None else EA,
            fixed=fixed,
            rest_length=rest_length,
            line_density=self.line_density,
            law=self.law_of(len(edges)),
            flies=flies,
        )

    def prestressed(self, net: Net) -> Net:
        """``net`` (under this material) with the rest lengths at which every edge carries
        the prestress in its given geometry; ``net`` itself without a prestress."""
        if self.prestress is None:
            return net
        length = np.linalg.norm(net.nodes[net.edges[:, 1]] - net.nodes[net.edges[:, 0]], axis=1)
        rest = prestressed_lengths(net.law, self.prestress, net.EA, length, _prestress_key)
        return net.with_rest_length(rest)


def _prestress_key(k: int) -> str:
    return "material.prestress"


def cable(
    start,
    end,
    nodes: int,
    material: Material,
    *,
    length: float | None = None,
) -> Net:
    """A single cable pinned at both ends, ``nodes`` nodes evenly on the chord.

    ``length`` is the unstressed length (default: the chord), shared equally by the
    ``nodes - 1`` edges. Node 0 is ``start``, node ``nodes - 1`` is ``end``.
    """
    start = np.asarray(start, dtype=np.float64)
    end = np.asarray(end, dtype=np.float64)
    if not 2 <= nodes <= MAX_NODES:
        raise ConfigError(f"geometry.nodes = {nodes}: must be in 2..{MAX_NODES}")
    _check_size(nodes, nodes - 1, f"geometry.nodes = {nodes}")
    chord = float(np.linalg.norm(end - start))
    if not chord > 0:
        raise ConfigError(f"geometry.end = {end.tolist()}: must differ from geometry.start")
    if length is None:
        length = chord
    if not (carried(length) and length > 0):
        raise ConfigError(f"geometry.length = {length!r}: must be finite and > 0, {WITHIN}")
    s = np.linspace(0.0, 1.0, nodes)
    xyz = start[None, :] + s[:, None] * (end - start)[None, :]
    edges = np.column_stack([np.arange(nodes - 1), np.arange(1, nodes)])
    rest = np.full(nodes - 1, length / (nodes - 1))
    return material.net(xyz, edges, fixed=[0, nodes - 1], rest_length=rest)


@dataclass(frozen=True)
class SquareNet:
    """The square net of the paper (Sec. 3.2) and the node whose deflection is reported."""

    net: Net
    center: int
    size: float
    n: int
    alpha: float
    cable: np.ndarray | None = None  # (M,) each edge's cable: A_k is k, B_j is m + j


def square_net(
    n: int, alpha: float, size: float, edge_length: float, material: Material
) -> SquareNet:
    """The paper's square net: ``n`` cables (``n/2`` per family) at angle ``alpha``.

    With d = L/(m+1), u = (cos a, sin a), v = (-sin a, cos a), c_k = (k - (m-1)/2) d:
    family A is the lines c_k v + t u, family B the lines -c_k u + t v, clipped to the
    square [-L/2, L/2]^2. Line A_k meets B_j at t = -c_j (on A_k) and t = c_k (on B_j).
    Every crossing is one shared node; each piece between break points gets
    ceil(length / edge_length - 1e-9) equal edges. Both ends of every cable are pinned.
    """
    _check_square(n, alpha, size, edge_length)
    made = _SquareNodes(_Cables.of(n, alpha, size))
    fixed: list[int] = []
    edges: list[np.ndarray] = []
    owner: list[np.ndarray] = []
    for line_id in range(n):
        breaks, ends = made.breaks(line_id)
        fixed.extend(ends)
        pieces = made.pieces(line_id, breaks, edge_length)
        edges += pieces
        owner += [np.full(len(p), line_id, dtype=np.int64) for p in pieces]
    xy = np.concatenate(made.points)
    nodes = np.column_stack([xy, np.zeros(len(xy))])
    edges_arr = np.concatenate(edges)
    try:
        net = material.unstressed(nodes, edges_arr, fixed=sorted(set(fixed)))
    except ConfigError as exc:  # e.g. edges that round to zero length in a tiny square
        raise ConfigError(
            [
                f"geometry.size = {size!r}, geometry.edge_length = {edge_length!r}: {p}"
                for p in exc.problems
            ]
        ) from None
    net = material.prestressed(net)
    center = int(np.argmin(np.hypot(nodes[:, 0], nodes[:, 1])))
    return SquareNet(
        net=net,
        center=center,
        size=float(size),
        n=int(n),
        alpha=float(alpha),
        cable=np.concatenate(owner),
    )


def square_net_cables(n: int) -> tuple[str, ...]:
    """The names of the square net's cables, in the order of ``SquareNet.cable``: A0 ..
    A(m-1) (family A, along u), then B0 .. B(m-1) (family B, along v)."""
    m = n // 2
    return tuple(f"A{k}" for k in range(m)) + tuple(f"B{k}" for k in range(m))


def _check_square(n: int, alpha: float, size: float, edge_length: float) -> None:
    """ConfigError for square-net keys out of range or a net too large to build."""
    if not (isinstance(n, (int, np.integer)) and n >= 2 and n % 2 == 0):
        raise ConfigError(f"geometry.n = {n!r}: must be an even integer >= 2")
    if not (carried(size) and size > 0):
        raise ConfigError(f"geometry.size = {size!r}: must be finite and > 0, {WITHIN}")
    if not (carried(edge_length) and edge_length > 0):
        raise ConfigError(
            f"geometry.edge_length = {edge_length!r}: must be finite and > 0, {WITHIN}"
        )
    if not math.isfinite(alpha):
        raise ConfigError(f"geometry.alpha = {alpha!r}: must be finite (radians)")
    m = n // 2
    # Each cable is at most L sqrt(2) long: a bound on the nodes before building anything.
    bound = m * m + n * (size * math.sqrt(2.0) / edge_length + 1.0)
    _check_size(bound, bound, f"geometry.edge_length = {edge_length!r}, geometry.n = {n}")


@dataclass(frozen=True)
class _Cables:
    """The square net's cables (``square_net``): m per family, the directions u and v,
    the offsets c_k, the tolerance 1e-9 L, and each line (origin p, direction w; A_k
    first, then B_j) with its parameter range [t0, t1] inside the square."""

    m: int
    u: np.ndarray
    v: np.ndarray
    c: np.ndarray
    tol: float
    lines: list[tuple[np.ndarray, np.ndarray]]
    spans: list[tuple[float, float]]

    @classmethod
    def of(cls, n: int, alpha: float, size: float) -> _Cables:
        """The ``n`` cables at angle ``alpha`` across the square of side ``size``."""
        m = n // 2
        L = float(size)
        half = 0.5 * L
        tol = 1e-9 * L
        d = L / (m + 1)
        u = np.array([math.cos(alpha), math.sin(alpha)])
        v = np.array([-math.sin(alpha), math.cos(alpha)])
        c = (np.arange(m) - (m - 1) / 2) * d
        # Lines: origin p, direction w. A_k: p = c_k v, w = u.  B_j: p = -c_j u, w = v.
        lines = [(ck * v, u) for ck in c] + [(-cj * u, v) for cj in c]
        spans = [_clip(p, w, half, tol) for p, w in lines]
        return cls(m, u, v, c, tol, lines, spans)


class _SquareNodes:
    """The square net's nodes as they are made: positions in blocks (one row per node,
    in the order of their ids; the nodes along a piece at once) and the crossings' ids."""

    def __init__(self, cables: _Cables) -> None:
        self.cables = cables
        self.points: list[np.ndarray] = []
        self.count = 0  # nodes made so far
        self.index: dict[tuple[int, int], int] = {}  # crossing (k, j) -> node id

    def add(self, block: np.ndarray) -> int:
        """Makes the nodes of ``block`` (rows of x, y); returns the first one's id."""
        self.points.append(block.reshape(-1, 2))
        self.count += self.points[-1].shape[0]
        return self.count - self.points[-1].shape[0]

    def crossing(self, k: int, j: int) -> int:
        """The node where A_k crosses B_j, made on first use."""
        if (k, j) not in self.index:
            c, u, v = self.cables.c, self.cables.u, self.cables.v
            self.index[(k, j)] = self.add(c[k] * v - c[j] * u)
        return self.index[(k, j)]

    def breaks(self, line_id: int) -> tuple[list[tuple[float, int]], list[int]]:
        """The break points (t, node id) of a line in order, its crossings and its ends,
        and its two end nodes (a crossing at an end, else a node of its own)."""
        cables = self.cables
        (p, w), (t0, t1) = cables.lines[line_id], cables.spans[line_id]
        m, c, tol = cables.m, cables.c, cables.tol
        family_a = line_id < m
        k = line_id if family_a else line_id - m
        found: list[tuple[float, int]] = []
        for other in range(m):
            t = -c[other] if family_a else c[other]
            if t0 - tol <= t <= t1 + tol:
                node = self.crossing(k, other) if family_a else self.crossing(other, k)
                found.append((min(max(t, t0), t1), node))
        found.sort()
        ends: list[int] = []
        for t_end in (t0, t1):
            near = [b for b in found if abs(b[0] - t_end) <= tol]
            if near:
                ends.append(near[0][1])
            else:
                ends.append(self.add(p + t_end * w))
                found.append((t_end, ends[-1]))
        found.sort()
        return found, ends

    def pieces(
        self, line_id: int, breaks: list[tuple[float, int]], edge_length: float
    ) -> list[np.ndarray]:
        """The edges of a line, a chain per piece between consecutive break points:
        ceil(length / edge_length - 1e-9) equal edges, their inner nodes made at once."""
        p, w = self.cables.lines[line_id]
        edges = []
        for (ta, na), (tb, nb) in zip(breaks[:-1], breaks[1:], strict=True):
            seg = tb - ta
            k_edges = max(1, math.ceil(seg / edge_length - 1e-9))
            steps = np.arange(1, k_edges)
            first = self.add(p + (ta + seg * steps / k_edges)[:, None] * w)
            chain = np.concatenate([[na], first + steps - 1, [nb]]).astype(np.int64)
            edges.append(np.column_stack([chain[:-1], chain[1:]]))
        return edges


def _clip(p: np.ndarray, w: np.ndarray, half: float, tol: float) -> tuple[float, float]:
    """Parameter range of the line p + t w inside the square |x|, |y| <= half."""
    lo, hi = -math.inf, math.inf
    for axis in range(2):
        if abs(w[axis]) < 1e-15:
            if abs(p[axis]) > half + tol:
                return (0.0, 0.0)
            continue
        a = (-half - p[axis]) / w[axis]
        b = (half - p[axis]) / w[axis]
        lo, hi = max(lo, min(a, b)), min(hi, max(a, b))
    if not hi - lo > tol:
        raise ConfigError("geometry: a cable of the square net misses the square")
    return (lo, hi)


def pressure_force(net: Net, pressure: float, size: float) -> np.ndarray:
    """The paper's distributed load: -p L^2 / N in z on every node (N = all nodes)."""
    f = np.zeros((net.n_nodes, 3))
    f[:, 2] = -pressure * size**2 / net.n_nodes
    return f


def graph(
    nodes,
    edges,
    fixed,
    material: Material,
    *,
    rest_length=None,
    EA=None,
    flies: bool = False,
) -> Net:
    """A net from explicit arrays under ``material``; ``EA`` per edge overrides the
    material's; ``flies``: parts of it may have no support (a net flying free in a
    dynamic run)."""
    return material.net(nodes, edges, fixed=fixed, EA=EA, rest_length=rest_length, flies=flies)
