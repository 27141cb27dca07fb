"""Utilisation of tension components: design tension over design resistance, per edge.

The rule is the cable resistance of EN 1993-1-11:2006 (tension components, groups B and
C), section 6:

    F_Ed / F_Rd <= 1,     F_Rd = min(F_uk / (1.5 gamma_R), F_k / gamma_R),
    F_uk = k_e F_min,     F_Ed = gamma_F T

with F_min the minimum breaking force of the cable (``material.breaking_load``), k_e the
loss factor of its end terminations (1.0 for metal or resin sockets, 0.9 for swaged
ones), F_k the characteristic proof force (its 0.2 % or 0.1 % proof load:
``material.proof_load``, optional: without it the first term alone decides), gamma_R the
partial factor and T the edge's tension as solved. gamma_R is a nationally determined
parameter; the edition's recommended values are 0.90 where measures limit bending at the
anchorages and 1.00 where none are taken. catenet cannot know which applies, so its
default is the larger, 1.00: give ``gamma_R = 0.9`` where the detailing limits bending,
or the national annex's value. gamma_F (``design.load_factor``, default 1) scales the
tension of every state: a combination whose factors already are the design factors of
EN 1990 needs none. Every factor is a key of ``[design]`` (``catenet.case.design``), so
that another edition or annex is a change of numbers, not of code. What of this was
checked against published text, and what not, is in docs/howto/reports.md ("The
utilisation rule").

An edge in compression (a strut) or slack has utilisation 0; an edge whose material
gives no breaking load has NaN (no resistance is known: "not checked"). A support may
have a capacity (``[[design.support]]``: its anchor's or fitting's design resistance
[N]); its utilisation is |R| / capacity.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: The defaults of [design]: EN 1993-1-11's factors, gamma_R the larger of its two
#: recommended values (no measures against bending at the anchorages assumed).
GAMMA_R = 1.00
BREAKING_FACTOR = 1.5
K_E = 1.0
LOAD_FACTOR = 1.0


@dataclass(frozen=True, eq=False)
class Design:
    """Per edge the minimum breaking force ``breaking_load`` (M,) [N] and the proof force
    ``proof_load`` (M,) [N] (NaN where a material gives none), and the factors of the rule
    (module docstring): ``gamma_R``, ``breaking_factor`` (the 1.5 on F_uk), ``k_e`` and
    ``load_factor`` (gamma_F)."""

    breaking_load: np.ndarray
    proof_load: np.ndarray
    gamma_R: float = GAMMA_R
    breaking_factor: float = BREAKING_FACTOR
    k_e: float = K_E
    load_factor: float = LOAD_FACTOR
    capacity: np.ndarray | None = None  # (N,) each support's capacity [N] (NaN: none)

    @classmethod
    def uniform(cls, n_edges: int, breaking_load: float | None, **factors) -> Design:
        """Every edge of one material (``breaking_load`` None: none given)."""
        value = np.nan if breaking_load is None else float(breaking_load)
        return cls(np.full(n_edges, value), np.full(n_edges, np.nan), **factors)

    @property
    def anchored(self) -> bool:
        """Whether any support has a capacity (``support_utilisation``)."""
        return self.capacity is not None and bool(np.isfinite(self.capacity).any())

    def support_utilisation(self, reaction: np.ndarray) -> np.ndarray:
        """|R| / capacity (N,) of the reactions ``reaction`` (N, 3) [N]: a support's
        anchor or fitting against its own resistance (no partial factor: give the design
        capacity); NaN where no capacity is given."""
        size = np.linalg.norm(np.asarray(reaction, dtype=np.float64), axis=-1)
        if self.capacity is None:
            return np.full(size.shape, np.nan)
        return size / self.capacity

    @property
    def given(self) -> bool:
        """Whether any edge has a breaking load (else every utilisation is NaN)."""
        return bool(np.isfinite(self.breaking_load).any())

    def resistance(self) -> np.ndarray:
        """F_Rd (M,) [N]: min(k_e F_min / (1.5 gamma_R), F_k / gamma_R), the second term
        only where a proof force is given; NaN where no breaking load is."""
        rd = self.k_e * self.breaking_load / (self.breaking_factor * self.gamma_R)
        proof = self.proof_load / self.gamma_R
        return np.where(np.isfinite(proof), np.fmin(rd, proof), rd)

    def utilisation(self, tension: np.ndarray) -> np.ndarray:
        """F_Ed / F_Rd (M,) of the tensions ``tension`` (M,) [N]: gamma_F max(T, 0) / F_Rd;
        NaN where no breaking load is given."""
        demand = self.load_factor * np.maximum(np.asarray(tension, dtype=np.float64), 0.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            return demand / self.resistance()
