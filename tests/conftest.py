"""Shared fixtures: small case files, the XDMF checker and subprocess helpers."""

from __future__ import annotations

import logging
import os
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]
CONFIGS = REPO / "configs"

# A small net (225 nodes) that settles in about 170 steps of 0.01 s.
SMALL_NET = """\
title = "small net"

[geometry]
kind = "square_net"
n = 10
alpha = 0.0
size = 1.0
edge_length = 0.05

[material]
E = 10e6
radius = 0.01
density = 1000.0

[load]
pressure = 100.0

[solver]
method = "{method}"
dt = {dt}
damping = {damping}
t_end = {t_end}

[output]
file = "out/small.h5"
every = {every}
"""


def small_net(method="dynamic", dt=0.01, damping=1.0, t_end=5.0, every=1) -> str:
    return SMALL_NET.format(method=method, dt=dt, damping=damping, t_end=t_end, every=every)


#: The root logger's level as the session began (a command run in the process changes it).
ROOT_LEVEL = logging.getLogger().level


@pytest.fixture(autouse=True)
def _logging_as_it_was():
    """A command run in this process (click's CliRunner: in a test or in a module's
    fixture) sets the root logger as ``catenet`` does (``setup_logging``: its level, a
    handler on the command's stderr). Each test starts and ends with the session's level
    and without such handlers (else a -q run leaves warnings filtered for every test
    after it on the worker, and caplog reads nothing)."""
    root = logging.getLogger()

    def restore() -> None:
        root.setLevel(ROOT_LEVEL)
        for handler in list(root.handlers):
            if type(handler) is logging.StreamHandler:  # catenet's, not pytest's
                root.removeHandler(handler)

    restore()
    yield
    restore()


@pytest.fixture
def write_case(tmp_path):
    """write_case(text, name="case.toml") -> path of a case file in tmp_path."""

    def write(text: str, name: str = "case.toml") -> Path:
        p = tmp_path / name
        p.write_text(text)
        return p

    return write


def catenet_command(*args: str) -> list[str]:
    """The command line that runs catenet in a fresh interpreter."""
    return [sys.executable, "-m", "catenet", *map(str, args)]


def subprocess_env() -> dict:
    env = dict(os.environ)
    env.pop("PYTHONWARNINGS", None)
    return env


def spawn(*args: str) -> subprocess.Popen:
    """``catenet *args`` in a fresh interpreter, its output captured as text."""
    return subprocess.Popen(
        catenet_command(*args),
        env=subprocess_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def wait_for_frames(path: Path, frames: int, proc: subprocess.Popen, timeout: float = 120.0):
    """Polls a result file that a subprocess writes until it has ``frames`` frames."""
    from catenet.output import open_result, trajectory_length

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            out, err = proc.communicate()
            raise AssertionError(f"catenet ended early ({proc.returncode}):\n{out}\n{err}")
        if path.exists():
            try:
                with open_result(path) as h5:
                    if trajectory_length(h5) >= frames:
                        return
            except (OSError, KeyError):
                pass  # not in SWMR mode yet, or the group is being created
        time.sleep(0.05)
    proc.kill()
    raise AssertionError(f"{path}: fewer than {frames} frames after {timeout} s")


def read_with_vtk(xdmf: Path):
    """An XDMF sidecar as VTK's XDMF reader (ParaView's) reads it, wrapped by pyvista
    (pyvista's own XdmfReader (0.49) fails on a file without times: it asks for the
    first time step), and the VTK errors and warnings it raised."""
    import pyvista as pv
    import vtk

    with pv.VtkErrorCatcher() as caught:
        reader = vtk.vtkXdmfReader()
        reader.SetFileName(str(xdmf))
        reader.Update()
        data = pv.wrap(reader.GetOutputDataObject(0))
    return data, caught.events


def check_xdmf(xdmf: Path) -> dict:
    """Parses an XDMF sidecar and checks every HDF5 reference in it against the file:
    the file exists (relative to the sidecar), the dataset exists with the declared shape,
    each per-frame view /xdmf/<name>/<k> holds frame k of /trajectory/<name> and each
    frame's time is /trajectory/time[k]. The file must open with a plain h5py.File(path,
    "r"). Returns counts for the caller ("slabs": the per-frame views named)."""
    import h5py

    tree = ET.parse(xdmf)
    root = tree.getroot()
    assert root.tag == "Xdmf" and root.get("Version") == "3.0"
    domain = root.find("Domain")
    assert domain is not None
    checked = {"refs": 0, "slabs": 0, "grids": 0, "times": []}
    views = set()
    with h5py.File(xdmf.parent / _h5_name(root), "r") as h5:
        for item in root.iter("DataItem"):
            assert item.get("Format") == "HDF", item.attrib  # meshio needs a Format
            assert item.get("ItemType") is None, item.attrib  # no HyperSlab (meshio)
            name, _, dataset = item.text.strip().partition(":")
            assert (xdmf.parent / name).is_file(), name
            assert dataset in h5, dataset
            dims = tuple(int(d) for d in item.get("Dimensions").split())
            assert h5[dataset].shape == dims, (dataset, h5[dataset].shape, dims)
            checked["refs"] += 1
            parts = dataset.strip("/").split("/")
            if parts[0] == "xdmf" and tuple(parts) not in views:
                views.add(tuple(parts))  # /xdmf/<source in /trajectory>/<k>
                k = int(parts[-1])
                source = h5["trajectory/" + "/".join(parts[1:-1])]
                assert k < source.shape[0], dataset
                assert np.array_equal(h5[dataset][()], source[k]), dataset
        checked["slabs"] = len(views)
        times = h5["trajectory/time"][()] if "trajectory/time" in h5 else np.zeros(0)
        checked["others"] = 0  # obstacles' and balls' grids
        # A modes file's animations (catenet.output.modes): a collection "mode k" each,
        # whose times are phases, not the trajectory's.
        animations = [g for g in domain if (g.get("Name") or "").startswith("mode ")]
        in_animation = {id(grid) for series in animations for grid in series.iter("Grid")}
        checked["modes"] = len(animations)
        for series in root.iter("Grid"):
            if series.get("CollectionType") == "Temporal" and id(series) not in in_animation:
                got = [float(g.find("Time").get("Value")) for g in series.findall("Grid")]
                assert got == list(times[: len(got)]), series.get("Name")
        for grid in root.iter("Grid"):
            if grid.get("GridType") != "Uniform" or id(grid) in in_animation:
                continue
            topo = grid.find("Topology")
            if topo.get("TopologyType") != "Polyline":  # an obstacle's surface or the balls
                assert topo.get("TopologyType") in ("Triangle", "Polyvertex"), grid.get("Name")
                cells = h5[topo.find("DataItem").text.strip().partition(":")[2]][()]
                points = grid.find("Geometry/DataItem").get("Dimensions").split()[0]
                assert len(cells) == int(topo.get("NumberOfElements"))
                assert cells.min() >= 0 and cells.max() < int(points), grid.get("Name")
                checked["others"] += 1
                continue
            checked["grids"] += 1
            topo = grid.find("Topology")
            assert topo.get("TopologyType") == "Polyline"
            assert topo.get("NodesPerElement") == "2"
            assert int(topo.get("NumberOfElements")) == len(h5["mesh/edges"])
            t = grid.find("Time")
            if t is not None:
                k = len(checked["times"])
                assert float(t.get("Value")) == times[k]
                checked["times"].append(float(t.get("Value")))
    return checked


def _h5_name(root) -> str:
    for item in root.iter("DataItem"):
        if item.get("Format") == "HDF":
            return item.text.strip().partition(":")[0]
    raise AssertionError("no HDF5 reference in the sidecar")


def pytest_configure(config):
    config.addinivalue_line(
        "markers", "slow: takes seconds (large nets, time stepping); still part of every run"
    )
    config.addinivalue_line(
        "markers",
        "roundoff: a verdict on a degenerate model (a mechanism, an indefinite or singular "
        "stiffness, a zero mode, a marginal contact); `make test` runs these once more with "
        "CATENET_ROUNDOFF=1 (every built net's coordinates moved by 1e-12 of its size, and "
        "two threads), so that a verdict that hangs on round-off fails here",
    )
    # One thread of MKL, OpenBLAS and Numba in each process, a run's default
    # (solver.threads = 1): for what tests call below the CLI (path.solve, the validation
    # cases). The libraries' own default, a thread per core in each of xdist's workers,
    # makes their spinning threads wait on each other (a 300 x 300 eigenvalue problem of a
    # stability verdict 8x slower). Tests of threading set their own counts.
    from catenet.solver.threads import set_threads

    set_threads(1)
    if os.environ.get("CATENET_ROUNDOFF"):
        _perturb_every_scene()


SLOW_WEIGHT = 10  # a test marked slow counts as this many others


def pytest_collection_modifyitems(config, items):
    """Whole files in order of their weight, the heaviest first (a stable sort: a file's
    tests keep their order): `make test` hands files to xdist's two workers in this order
    (``--no-loadscope-reorder``), so that the long ones start early and the short ones
    fill the end, where one long file started last would leave the other worker idle."""
    weight: dict = {}
    for item in items:
        slow = item.get_closest_marker("slow") is not None
        weight[item.path] = weight.get(item.path, 0) + (SLOW_WEIGHT if slow else 1)
    items.sort(key=lambda item: -weight[item.path])


ROUNDOFF = 1e-12  # CATENET_ROUNDOFF: the relative move of every node of every built net
ROUNDOFF_THREADS = 2  # ... and the threads every solve uses


def _perturb_every_scene() -> None:
    """The round-off pass (CATENET_ROUNDOFF=1): every scene built from a case has its
    nodes (supports included) moved by ROUNDOFF of the net's size in a seeded random
    direction, and every run uses ROUNDOFF_THREADS threads: a verdict that changes with
    either was decided by round-off."""
    import catenet.case as case_pkg
    import catenet.case.scene as scene_mod
    import catenet.solver.threads as threads_mod

    build = scene_mod.build

    def perturbed(case):
        scene = build(case)
        nodes = scene.net.nodes
        size = float(np.max(np.ptp(nodes, axis=0))) if nodes.size else 1.0
        rng = np.random.default_rng(12345)
        nodes += ROUNDOFF * max(size, 1e-300) * rng.uniform(-1.0, 1.0, nodes.shape)
        return scene

    scene_mod.build = perturbed
    case_pkg.build = perturbed
    set_threads = threads_mod.set_threads
    threads_mod.set_threads = lambda threads: set_threads(max(threads, ROUNDOFF_THREADS))


# --- the examples in configs/, each run once per test session ------------------------------


@pytest.fixture(scope="session")
def example(tmp_path_factory):
    """``example(name)``: the result file of ``configs/<name>.toml`` as ``catenet run``
    writes it. Each example runs once per test session, also when the tests that need it
    are spread over xdist's worker processes: the first to ask runs it into a directory
    the workers share, under a lock; the others read its file."""
    import fcntl
    import hashlib

    from catenet.case import load_case
    from catenet.run.runner import run_case

    base = tmp_path_factory.getbasetemp()
    shared = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base
    root = shared / "examples"
    root.mkdir(exist_ok=True)

    def run(name: str) -> Path:
        source = CONFIGS / f"{name}.toml"
        digest = hashlib.sha256(source.read_bytes()).hexdigest()[:12]
        out = root / f"{name.replace('/', '-')}-{digest}.h5"
        with open(out.with_suffix(".lock"), "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            if not out.exists():
                run_case(load_case(source), out)
        return out

    return run
