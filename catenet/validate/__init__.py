"""Validation: the closed forms (``analytic``) and the table of ``catenet validate``."""
