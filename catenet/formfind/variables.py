"""The design variables of form finding's elastic method (``formfind.method =
"elastic"``): s -> the rest lengths l0 of the net, and dl0/ds.

``vary = "cables"`` (the default) or ``"edges"``: a factor c on the case's rest lengths
of each cable (a graph's own edges one each; a net without named cables one for all) or
of each edge, s = log c, bounded by ``formfind.rest_length_factor_min`` / ``_max``.
``vary = "prestress"``: the prestress T [N] of each named cable that has one > 0 in the
case (its own ``prestress``, its material's, or [material] prestress; a net without named
cables: [material] prestress for all; a strut's compression is kept), s = log T; each
edge of the cable has the rest length l0 = L / (1 + T / EA) at which it carries T in the
given geometry (L its length there: how the case derives it), bounded by
``formfind.prestress_min`` / ``_max``. Other edges keep their rest lengths.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from catenet.errors import ConfigError
from catenet.formfind.anchors import Anchors, support_moves

if TYPE_CHECKING:
    import scipy.sparse as sp


class Variables:
    """s -> rest lengths and support positions; ``groups`` (M,) the rest-length variable
    of each edge (-1: none), ``moves`` the supports' (nodes, axis, name), their variables
    after the rest lengths' (``n_rest``) as offsets over the net's size; ``start`` and
    ``bounds`` (lo, hi) in s, ``names`` (one per variable: the cable's, where named, and
    each support offset's)."""

    def __init__(
        self, scene, vary: str, bounds: tuple, prefix: str = "formfind.", moves: tuple = ()
    ):
        from catenet.formfind.design import _groups

        net = scene.net
        self.kind = {"prestress": "prestress", "supports": "offset"}.get(vary, "factor")
        self.base = net.rest_length.copy()
        self.names: list[str] = []
        if vary == "supports":  # (the rest lengths kept)
            self.groups = np.full(net.n_edges, -1, dtype=np.int64)
            start = np.zeros(0)
        elif self.kind == "prestress":
            self.groups, t0, self.names = _prestressed(scene, prefix)
            ends = net.nodes[net.edges[:, 1]] - net.nodes[net.edges[:, 0]]
            self.length = np.linalg.norm(ends, axis=1)
            self.EA = np.asarray(net.EA, dtype=np.float64)
            start = np.log(t0)
        else:
            self.groups = np.zeros(net.n_edges, dtype=np.int64)
            if vary == "edges" or (scene.cables is not None and scene.cables.names):
                self.groups = _groups(scene, vary, prefix)
            if vary == "cables" and scene.cables is not None and scene.cables.names:
                self.names = list(scene.cables.names)
            start = np.zeros(int(self.groups.max()) + 1)
        self.n_rest = len(start)
        lo = -np.inf if bounds[0] is None else math.log(bounds[0])
        hi = np.inf if bounds[1] is None else math.log(bounds[1])
        low, high = [np.full(self.n_rest, lo)], [np.full(self.n_rest, hi)]
        starts = [np.clip(start, lo, hi)]
        self.nodes0 = net.nodes.copy()
        self.size = float(np.linalg.norm(np.ptp(net.nodes, axis=0))) or 1.0
        self.moves = support_moves(scene, moves, prefix)
        self.anchors = Anchors(net, self.moves, self.n_rest, self.size)
        a_lo, a_hi, a_start = self.anchors.bounds()  # (offsets over the size: s's scale)
        low.append(a_lo)
        high.append(a_hi)
        starts.append(a_start)
        if self.moves:  # (names line up with the values, "" unnamed: the offsets' last)
            self.names += [""] * (self.n_rest - len(self.names))
            self.names += [name for _, _, name, _ in self.moves]
        self.bounds = (np.concatenate(low), np.concatenate(high))
        self.start = np.concatenate(starts)
        self.n = len(self.start)
        self.on = self.groups >= 0

    def rest(self, s: np.ndarray) -> np.ndarray:
        """The rest lengths (M,) at s."""
        l0 = self.base.copy()
        g = self.groups[self.on]
        v = np.exp(np.clip(s[: self.n_rest], -700.0, 700.0))[g]
        if self.kind == "prestress":
            l0[self.on] = self.length[self.on] / (1.0 + v / self.EA[self.on])
        else:
            l0[self.on] = self.base[self.on] * v
        return l0

    def positions(self, s: np.ndarray) -> np.ndarray:
        """The nodes (N, 3) at s: the supports moved by their offsets."""
        x = self.anchors.positions(s)
        return self.nodes0.copy() if x is None else x

    def moved(self, j: int) -> np.ndarray:
        """dx/ds (N, 3) of the j-th support offset."""
        nodes, c, _, _ = self.moves[j]
        out = np.zeros_like(self.nodes0)
        out[nodes, c] = self.size
        return out

    def jacobian(self, s: np.ndarray) -> sp.csr_matrix:
        """dl0/ds (M, n), sparse (the support offsets' columns empty)."""
        import scipy.sparse as sp

        e = np.flatnonzero(self.on)
        g = self.groups[e]
        v = np.exp(s[: self.n_rest])[g]
        if self.kind == "prestress":
            ea, length = self.EA[e], self.length[e]
            d = -length / ea / (1.0 + v / ea) ** 2 * v  # dl0/dT T
        else:
            d = self.base[e] * v
        return sp.csr_matrix((d, (e, g)), shape=(len(self.groups), self.n))

    def values(self, s: np.ndarray) -> np.ndarray:
        """The variables themselves: the factors, or the prestresses [N], then the
        supports' offsets [m]."""
        return np.concatenate([np.exp(s[: self.n_rest]), self.anchors.offsets(s)])

    def at_bound(self, s: np.ndarray) -> int:
        return int(np.count_nonzero(self.bound(s)))

    def bound(self, s: np.ndarray) -> np.ndarray:
        """Per variable: whether it is at one of its bounds."""
        lo, hi = self.bounds
        return (s <= lo + 1e-12) | (s >= hi - 1e-12)


def _prestressed(scene, prefix: str) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """(groups, T0, names) of the cables with a prestress in the case."""
    from catenet.case.keys import Checker
    from catenet.case.kinds.cables import cable_materials

    case, net = scene.case, scene.net
    cables = getattr(case.geometry, "cables", ()) or ()
    groups = np.full(net.n_edges, -1, dtype=np.int64)
    t0: list[float] = []
    names: list[str] = []
    if scene.cables is not None and scene.cables.names and cables:
        mats = cable_materials(Checker(), case.material, cables)
        edge = np.asarray(scene.cables.edge)
        for c, (cable, mat) in enumerate(zip(cables, mats, strict=True)):
            t = getattr(mat, "prestress", None)
            sel = edge == c
            if t is None or not t > 0 or not sel.any():  # (a strut's compression: kept)
                continue
            groups[sel] = len(t0)
            t0.append(float(t))
            names.append(cable.name)
    elif (getattr(case.material, "prestress", None) or 0.0) > 0:
        groups[:] = 0
        t0.append(float(case.material.prestress))
        names.append("material")
    if not t0:
        raise ConfigError(
            f"{prefix}vary = 'prestress': no cable of this case has a prestress > 0 (a "
            "graph's [[geometry.cable]] prestress, its material's, or [material] prestress): "
            "give the cables to vary theirs, or vary = 'cables'"
        )
    return groups, np.asarray(t0), names


__all__ = ["Variables"]
