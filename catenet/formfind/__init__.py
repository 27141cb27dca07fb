"""Form finding: the shape of a net that carries chosen forces (``catenet formfind``).

``fdm`` is the force density method on a net (``formfind``, ``FormFound``); ``case``
form-finds a case with a [formfind] table and writes the graph case that ``catenet run``
reproduces the shape with, and the result file (``write_formfind``, ``to_case``);
``design`` finds the force densities that reach a case's [[target]] tables
(``formfind_targets``: ``goals``, ``adjoint``, ``levenberg``, ``surface``, ``report``),
``elastic`` the rest lengths that reach them in the elastic equilibrium.
"""

from catenet.formfind.case import Written, case_file_for, formfind_scene, to_case, write_formfind
from catenet.formfind.fdm import METHODS, FormFound, Pattern, formfind, per_edge

__all__ = [
    "METHODS",
    "FormFound",
    "Pattern",
    "Written",
    "case_file_for",
    "formfind",
    "formfind_scene",
    "per_edge",
    "to_case",
    "write_formfind",
]
