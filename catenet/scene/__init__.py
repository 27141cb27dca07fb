"""The scene layer, between the energy terms and the solver: what a scene is made of,
in typed objects that a case file and a Python script build alike. ``shapes``: one
module per obstacle shape, each a class of the ``Shape`` protocol (its barrier, first
hit, outline, mass properties and surface mesh)."""

from catenet.scene.scene import Scene

__all__ = ["Scene"]
