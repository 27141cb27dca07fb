"""Reading a mesh file with meshio (a net's ``geometry.file``, a mesh obstacle, a form
finding's target surface): every way meshio fails, its own exit and messages included,
as one ValueError."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path
from typing import Any


def read_mesh_file(path: str | Path) -> Any:
    """``meshio.read(path)``; ValueError with a one-line reason when it cannot be read
    (meshio raises many kinds of exceptions, and for some files prints a line and calls
    ``sys.exit``). ImportError when meshio is missing."""
    import meshio
    import numpy as np

    said = io.StringIO()
    try:
        with (
            np.errstate(over="ignore"),  # meshio's binary-STL size test on ASCII files
            contextlib.redirect_stdout(said),
            contextlib.redirect_stderr(said),
        ):
            return meshio.read(path)
    except (Exception, SystemExit) as exc:
        text = str(exc).strip() if not isinstance(exc, SystemExit) else ""
        text = text or said.getvalue().strip() or type(exc).__name__
        raise ValueError(text.splitlines()[0].removeprefix("Error: ")) from None


def read_triangles(path: str | Path, what: str) -> tuple[Any, Any]:
    """(points (P, 3) as floats, triangles (T, 3)) of the triangle cells of a mesh file;
    ValueError with the reason (meshio missing or failing, no triangle cells), ``what``
    naming the file's role in it ("a mesh obstacle", "a surface")."""
    import numpy as np

    try:
        mesh = read_mesh_file(path)
    except ImportError:
        raise ValueError(
            f"reading {what} needs the Python package meshio (pip install meshio)"
        ) from None
    except ValueError as exc:
        raise ValueError(f"meshio cannot read it: {exc}") from None
    tris = [np.asarray(c.data, dtype=np.int64) for c in mesh.cells if c.type == "triangle"]
    if not tris:
        found = ", ".join(sorted({c.type for c in mesh.cells})) or "no cells"
        raise ValueError(f"holds no triangles (it has {found}): {what} is a triangle surface")
    return np.asarray(mesh.points, dtype=np.float64), np.concatenate(tris)
