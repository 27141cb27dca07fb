"""Closed-form answers for the tests (STYLE: tests/analytic.py).

The closed forms and their derivations live in ``catenet.analytic``, because
``catenet validate`` needs them at run time; this module re-exports them so that tests
can write ``from analytic import elastic_catenary``. See ``catenet/analytic.py`` for the
derivation of every formula (paper Eqs. 14-17, the exact elastic catenary of Irvine,
*Cable Structures*, 1981, and the exact discrete chain).
"""

from catenet.analytic import (
    DiscreteCatenary,
    ElasticCatenary,
    catenary_parameter,
    catenary_sag,
    catenary_shape,
    discrete_catenary,
    elastic_catenary,
    midpoint_load_deflection,
    midpoint_load_force,
    midpoint_load_shape,
)

__all__ = [
    "DiscreteCatenary",
    "ElasticCatenary",
    "catenary_parameter",
    "catenary_sag",
    "catenary_shape",
    "discrete_catenary",
    "elastic_catenary",
    "midpoint_load_deflection",
    "midpoint_load_force",
    "midpoint_load_shape",
]
