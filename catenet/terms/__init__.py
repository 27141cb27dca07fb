"""Energy terms: every physical contribution to the potential the solvers minimise.

``Stretch`` (the edges under their material law), ``ExternalForce`` (nodal forces,
pressure, gravity) and ``Inertia`` (the dynamic step's inertia and damping) are the
paper's; a scene may name more (``Scene.terms``). Each implements ``Term`` and is known by
name in ``TERMS``; see ``catenet.terms.base``.
"""

from catenet.terms.base import TERMS, Term, check_derivatives, node_block_pattern, register
from catenet.terms.inertia import Inertia
from catenet.terms.loads import ExternalForce
from catenet.terms.stretch import Stretch

__all__ = [
    "TERMS",
    "ExternalForce",
    "Inertia",
    "Stretch",
    "Term",
    "check_derivatives",
    "node_block_pattern",
    "register",
]
