"""The engine: the system (pattern and values), the linear solver, Newton, static and
dynamic solves, time integrators, the one solve path (``path``) and its result."""
