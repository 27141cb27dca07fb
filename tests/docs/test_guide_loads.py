"""docs/guide/loads.md runs as written: its case files and nets are written, its commands
succeed or fail with the message it shows."""

from __future__ import annotations

import shutil

import h5py
import numpy as np
from pages import ROOT, run_page, steps

PAGE = ROOT / "docs" / "guide" / "loads.md"


def test_the_page_has_its_examples():
    found = steps(PAGE)
    files = {s.name for s in found if s.kind == "file"}
    assert {"strip.toml", "regions.toml", "missed.toml", "net.obj", "from_obj.toml"} <= files
    errors = [s.error for s in found if s.kind == "shell" and s.error]
    assert len(errors) == 3


def test_the_page_runs_as_written(tmp_path, monkeypatch):
    shutil.copytree(ROOT / "configs", tmp_path / "configs")
    monkeypatch.chdir(tmp_path)
    run_page(PAGE, tmp_path)
    with h5py.File(tmp_path / "out" / "hypar_roof.h5") as h5:
        reaction = h5["result/reaction"][:]
        assert h5["result"].attrs["converged"]
    assert reaction[:, 2].sum() > 800.0 * 144.0  # the snow and the self-weight
    with h5py.File(tmp_path / "out" / "regions.h5") as h5:
        fixed = h5["mesh/fixed"][:]
        nodes = h5["mesh/nodes"][:]
        names = h5["mesh"].attrs["cable_names"].astype(str).tolist()
    assert np.array_equal(np.flatnonzero(fixed), np.flatnonzero(np.isin(nodes[:, 0], [0, 10])))
    assert names == ["south", "middle", "north"]
    with h5py.File(tmp_path / "out" / "from_obj.h5") as h5:
        assert h5["mesh"].attrs["cable_names"].astype(str).tolist() == ["main", "cross"]
