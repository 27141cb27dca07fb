"""The flush study (``benchmarks/flush.py``): its per-frame writer stores what catenet's
writer stores."""

from __future__ import annotations

import tomllib

import h5py
import numpy as np
from conftest import small_net

from catenet.output import ResultWriter, open_result


def make_scene(**kw):
    from catenet.case import build, parse_case

    return build(parse_case(tomllib.loads(small_net(**kw))))


def moved(scene, k):
    x = scene.net.nodes.copy()
    x[~scene.net.fixed, 2] -= 0.001 * k
    return x


def test_the_flush_studys_per_frame_writer_stores_what_the_writer_stores(tmp_path):
    """``python -m benchmarks flush`` compares the writer with catenet's earlier per-frame SWMR
    writer: both store the same frames, bit for bit."""
    from benchmarks.flush import swmr_writer_class

    scene = make_scene()
    rng = np.random.default_rng(3)
    frames = [(0.1 * k, moved(scene, k) + rng.random((scene.net.n_nodes, 3))) for k in range(5)]
    for name, cls in (("old.h5", swmr_writer_class()), ("new.h5", ResultWriter)):
        with cls(tmp_path / name, scene, every=1) as w:
            for t, x in frames:
                w.frame(t, x, 2 * x)
    with h5py.File(tmp_path / "new.h5", "r") as new, open_result(tmp_path / "old.h5") as old:
        for name in ("time", "x", "v", "tension"):
            np.testing.assert_array_equal(new["trajectory"][name], old["trajectory"][name])
