"""Figures of ``catenet plot``: the figure, and the balls and obstacles drawn in it."""
