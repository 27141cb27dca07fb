"""Closed-form answers for the tests (STYLE: tests/analytic.py).

The closed forms and their derivations live in ``catenet.validate.analytic``, because
``catenet validate`` needs them at run time; this module re-exports them so that tests
can write ``from analytic import elastic_catenary``. See ``catenet/validate/analytic.py`` for the
derivation of every formula (paper Eqs. 14-17, the exact elastic catenary of Irvine,
*Cable Structures*, 1981, and the exact discrete chain).
"""

from catenet.validate import analytic as _analytic
from catenet.validate.analytic import *  # noqa: F403  (the closed forms, re-exported)

__all__ = list(_analytic.__all__)
