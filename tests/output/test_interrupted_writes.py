"""A write of the result file broken off at any point (Ctrl-C, a signal handler raising in
the middle of HDF5 calls) leaves the published file intact, and the writer's next flush
writes everything again from it: no "name already exists", no frame lost or doubled."""

from __future__ import annotations

import os
import tomllib

import h5py
import numpy as np
import pytest
from conftest import check_xdmf, small_net

import catenet.output.writer as writer_module
from catenet.output import ResultWriter
from catenet.solver.result import Result


class Stop(BaseException):
    """Raised where a signal handler would raise: not an Exception the writer handles."""


def make_scene():
    from catenet.case import build, parse_case

    return build(parse_case(tomllib.loads(small_net())))


def moved(scene, k):
    x = scene.net.nodes.copy()
    x[~scene.net.fixed, 2] -= 0.001 * k
    return x


def once(real, *, before: bool = False):
    """``real`` wrapped to raise Stop on its first call (after doing its work, or
    ``before`` it)."""
    calls = []

    def wrapped(*args, **kw):
        calls.append(1)
        if len(calls) == 1 and before:
            raise Stop
        out = real(*args, **kw)
        if len(calls) == 1:
            raise Stop
        return out

    return wrapped


def half_published(spare, path, prev):
    """``files.publish`` stopped between its two renames: the new version is the result
    file, the spare is gone, the old version lies at ``prev``."""
    prev.unlink(missing_ok=True)
    os.link(path, prev)
    os.replace(spare, path)
    raise Stop


def result_of(scene, x):
    return Result(
        x=x,
        tension=np.zeros(scene.net.n_edges),
        reaction=np.zeros_like(x),
        converged=True,
        iterations=1,
        residual=0.0,
        steps=4,
        time=0.3,
        equilibrium=True,
        message="done",
    )


def once_publish(real):
    """``files.publish`` stopped between its two renames on its first call."""
    calls = []

    def wrapped(spare, path, prev):
        calls.append(1)
        if len(calls) == 1:
            half_published(spare, path, prev)
        return real(spare, path, prev)

    return wrapped


BREAKS = {  # where in a write it breaks off: the writer's name, and the break
    "in the views": ("write_views", once),
    "in the trajectory": ("append_frames", once),
    "before the times": ("append_times", lambda real: once(real, before=True)),
    "between the renames": ("publish", once_publish),
}


@pytest.mark.parametrize("where", list(BREAKS))
@pytest.mark.parametrize("at", [1, 2, 3], ids=["call1", "call2", "call3"])
@pytest.mark.parametrize("update", ["append", "copy"])
def test_a_write_broken_off_is_done_again_from_the_published_file(tmp_path, where, at, update):
    """Frames 1-3 are written one flush each (the spare brought up to date after each
    publication by appending, or by copying the file); the ``at``-th call of a write step
    breaks off. The frame being written then is written again with the next flush: the file
    holds frames 0-3 bit for bit, /result, a sidecar whose views hold their frames, no spare."""
    name, wrap = BREAKS[where]
    scene = make_scene()
    path = tmp_path / "run.h5"
    real = getattr(writer_module, name)
    broken = wrap(real)
    calls: list[int] = []
    stopped = []

    def counting(*args, **kw):
        calls.append(1)
        return (broken if len(calls) == at else real)(*args, **kw)

    with ResultWriter(path, scene, every=1, flush_frames=1) as w:
        w.frame(0.0, moved(scene, 0))
        w._copy_rate = 1.0 if update == "append" else 0.0  # s per byte: the way chosen
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(writer_module, name, counting)
            for k in (1, 2, 3):
                try:
                    w.frame(0.1 * k, moved(scene, k))
                except Stop:
                    stopped.append(k)
                    with h5py.File(path, "r") as h5:  # the published file reads at once
                        assert h5["trajectory/time"].shape[0] in (k, k + 1)
            w.result(result_of(scene, moved(scene, 3)))
    assert len(stopped) == 1, (stopped, len(calls))  # the break was reached, once
    with h5py.File(path, "r") as h5:
        np.testing.assert_array_equal(h5["trajectory/time"][()], [0.1 * k for k in range(4)])
        for k in range(4):
            np.testing.assert_array_equal(h5["trajectory/x"][k], moved(scene, k))
        np.testing.assert_array_equal(h5["result/x"][()], moved(scene, 3))
    assert check_xdmf(path.with_suffix(".xdmf"))["grids"] == 4
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.h5", "run.xdmf"]


def test_a_result_write_broken_off_is_written_whole_on_the_next_try(tmp_path):
    """Ctrl-C while /result is half written (its group made): the run's cleanup writes the
    result again and the file holds it once, complete."""
    scene = make_scene()
    path = tmp_path / "run.h5"
    real = writer_module.write_result_group
    with ResultWriter(path, scene, every=1, flush_frames=1) as w:
        w.frame(0.0, moved(scene, 0))
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(writer_module, "write_result_group", once(real))
            with pytest.raises(Stop):
                w.result(result_of(scene, moved(scene, 0)))
            with h5py.File(path, "r") as h5:
                assert "result" not in h5  # the published file never saw the half
            w.result(result_of(scene, moved(scene, 1)))
    with h5py.File(path, "r") as h5:
        np.testing.assert_array_equal(h5["result/x"][()], moved(scene, 1))
        assert h5["trajectory/time"].shape == (1,)
