"""Reading a mesh file with meshio (a net's ``geometry.file``, a mesh obstacle):
every way meshio fails, its own exit and messages included, as one ValueError."""

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
