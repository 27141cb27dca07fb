"""Anderson acceleration of a fixed point m = G(m) (Walker and Ni 2011, "type II"): the
next iterate mixes the last ``depth`` values of G so that the mix of their residuals
F = G(m) - m is least in the 2-norm,

    m_next = G_k - dG gamma,   gamma = argmin |F_k - dF gamma|,

dF and dG the differences of successive residuals and values. Where G is nearly linear
with a slow rate (the self-weight of a sagging net: 0.86 a load update at a spider net's
15 N/m, where plain updates took hundreds), the mix converges in a few tens of updates; it
finds fixed points that plain updates leave (a rate beyond 1) as well.

Used by the force density method's self-weight (``catenet.formfind.fdm``): ``m`` is the
nodes' lumped masses, which must stay >= 0; a mix that makes any negative is dropped for
the plain update G_k, and the history restarts. The spider net of configs/formfind/
took 21, 13, 11 and 7 load updates at 15, 20, 50 and 500 N/m from no weight (17, 14,
10 and 6 from the given net's), where plain updates took more than 100, 46, 24 and 8.
"""

from __future__ import annotations

import numpy as np

DEPTH = 5  # differences kept


class Anderson:
    """The mixing of one fixed-point iteration (module docstring)."""

    def __init__(self, depth: int = DEPTH):
        self.depth = depth
        self._f: list[np.ndarray] = []  # the last residuals F
        self._g: list[np.ndarray] = []  # ... and values G

    def mix(self, m: np.ndarray, g: np.ndarray) -> np.ndarray:
        """The next iterate after m, whose value G(m) is ``g``."""
        self._f.append(g - m)
        self._g.append(g.copy())
        if len(self._f) > self.depth + 1:
            self._f.pop(0)
            self._g.pop(0)
        if len(self._f) < 2:
            return g.copy()
        dF = np.column_stack([b - a for a, b in zip(self._f, self._f[1:], strict=False)])
        dG = np.column_stack([b - a for a, b in zip(self._g, self._g[1:], strict=False)])
        gamma = np.linalg.lstsq(dF, self._f[-1], rcond=1e-12)[0]
        out = g - dG @ gamma
        if not (np.all(np.isfinite(out)) and np.all(out >= 0.0)):
            self._f, self._g = self._f[-1:], self._g[-1:]  # restart from the plain update
            return g.copy()
        return out
