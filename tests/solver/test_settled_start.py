"""A given geometry that is unstable but no equilibrium is judged at the stable equilibrium
Newton finds from it under its prestress (``catenet.solver.loadsteps._settled``).

Found on a newcomer's model: the guyed mast that ``catenet formfind`` wrote (one strut, 90
kN in it, three sagging guys with prestress), its free nodes moved by 1e-4 of its size
(about 6 mm) to check that the rest lengths, not the coordinates, carry the shape. The
guys had slack edges in that geometry, one of them its top edge, so across that guy the
strut's top was held by nothing but the strut's own negative stiffness, and the run
stopped: "the given geometry is unstable under its
prestress, so any load folds it: a mechanism ... at nodes 1". The equilibrium one Newton
iteration away is stable, and the dynamic method reached it."""

from __future__ import annotations

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from catenet.cli import main

MAST = """
[geometry]
kind = "graph"
nodes = {nodes}
sets = {{ foot = [0], top = [1], anchors = [2, 3, 4] }}

[[geometry.cable]]
name = "mast"
nodes = {mast}
rest_length = {mast_l0}
material = {{ EA = 2.0e9, tension_only = false, density = 0.0 }}

[[geometry.cable]]
name = "guyA"
nodes = [1, {a}, 2]
rest_length = {guy_l0}

[[geometry.cable]]
name = "guyB"
nodes = [1, {b}, 3]
rest_length = {guy_l0}

[[geometry.cable]]
name = "guyC"
nodes = [1, {c}, 4]
rest_length = {guy_l0}

[supports]
fixed = ["foot", "anchors"]

[material]
E = 1.6e11
radius = 0.012
density = 7850.0

[load]
gravity = [0.0, 0.0, -9.81]

[[load.point]]
node = "top"
force = [8.0e3, 0.0, 0.0]
"""

GUY_NODES = 9  # interior nodes per guy
PRESTRESS = 40.0e3  # [N] in the guys, their rest lengths made from it on their chords
GUY_EA = 1.6e11 * np.pi * 0.012**2


def _mast(shift: float = 0.0, seed: int = 0, hinge: bool = False) -> str:
    """The 40 m mast on three guys to anchors 30 m out (50 m chords), their rest lengths
    as given (PRESTRESS on the chords), the guys' interior nodes on their chords; every
    free node moved by up to ``shift`` of the size (seeded); ``hinge``: the strut in two
    edges, pinned at its middle."""
    top = np.array([0.0, 0.0, 40.0])
    anchors = [
        30.0 * np.array([np.cos(a), np.sin(a), 0.0]) for a in (0.0, 2 * np.pi / 3, -2 * np.pi / 3)
    ]
    nodes = [np.zeros(3), top, *anchors]
    guys = []
    for anchor in anchors:
        first = len(nodes)
        s = np.linspace(0.0, 1.0, GUY_NODES + 2)[1:-1]
        nodes.extend(top + t * (anchor - top) for t in s)
        guys.append(", ".join(str(k) for k in range(first, len(nodes))))
    mast = '["foot", "top"]'
    if hinge:
        mast = f'["foot", {len(nodes)}, "top"]'
        nodes.append(0.5 * top)
    x = np.array(nodes)
    free = np.ones(len(x), bool)
    free[[0, 2, 3, 4]] = False
    size = float(np.linalg.norm(np.ptp(x, axis=0)))
    x[free] += shift * size * np.random.default_rng(seed).uniform(-1.0, 1.0, (free.sum(), 3))
    guy_l0 = [50.0 / (GUY_NODES + 1) / (1.0 + PRESTRESS / GUY_EA)] * (GUY_NODES + 1)
    mast_l0 = [20.0, 20.0] if hinge else [40.0]
    return MAST.format(
        nodes=x.tolist(), mast=mast, mast_l0=mast_l0, guy_l0=guy_l0, a=guys[0], b=guys[1], c=guys[2]
    )


def _run(tmp_path, text: str, name: str):
    case = tmp_path / f"{name}.toml"
    case.write_text(text)
    out = tmp_path / f"{name}.h5"
    done = CliRunner().invoke(main, ["run", str(case), "-o", str(out)])
    return done, out


def _top(out) -> np.ndarray:
    with h5py.File(out, "r") as f:
        return np.asarray(f["/result/x"][1])


@pytest.mark.parametrize("shift", [1e-12, 1e-4, 1e-3])
@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("threads", [1, 2])
def test_a_guyed_mast_moved_off_its_equilibrium_is_no_mechanism(tmp_path, shift, seed, threads):
    """From every start, on one thread and two, the run ends stable at the equilibrium of
    the mast given on its chords (its top to 1e-6 m), exit 0: no mechanism, no collapse."""
    ref, ref_out = _run(tmp_path, _mast(), "ref")
    assert ref.exit_code == 0, ref.output
    text = _mast(shift, seed) + f"\n[solver]\nthreads = {threads}\n"
    done, out = _run(tmp_path, text, "moved")
    assert done.exit_code == 0, done.output
    assert "mechanism" not in done.output and "collapse" not in done.output
    with h5py.File(out, "r") as f:
        assert bool(f["/result"].attrs["converged"])
    assert np.allclose(_top(out), _top(ref_out), rtol=0.0, atol=1e-6)


def test_a_strut_of_two_pinned_edges_moved_off_its_line_stays_a_mechanism(tmp_path):
    """The mast split at its middle into two pinned edges (nothing holds the hinge) is a
    mechanism from a start moved off its line too: Newton finds no stable equilibrium
    near it, and the verdict stands."""
    text = _mast(1e-4, 0, hinge=True)
    done, _ = _run(tmp_path, text, "hinged")
    assert done.exit_code != 0, done.output
    assert "mechanism" in done.output
