"""Contact scenes and terms the tests of catenet/terms/ share: a block on a rough plane
(friction), boxes, capsules and meshes on a prescribed motion, a net pressed onto a box,
the tether capture scene close to its box, and a net catching a ball."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from meshes import CUBE_T, CUBE_V
from scipy.optimize import brentq

from catenet.kernels.contact import barrier
from catenet.model.net import Loads, Net
from catenet.scene import Scene
from catenet.terms.contact import PlaneBarrier
from catenet.terms.friction import Friction
from catenet.terms.moving import Moving
from catenet.terms.shapes import BoxBarrier, CapsuleBarrier, MeshBarrier, rotation

# --- friction: a block on a plane ---------------------------------------------------------

KAPPA, DHAT = 1e4, 1e-2


def resting_gap(force: float) -> float:
    """The gap at which the plane barrier carries ``force``."""
    return brentq(lambda d: -KAPPA * barrier(d, DHAT)[1] - force, 1e-12, DHAT * (1 - 1e-12))


def block(*, mu, slip, force, mass=0.0, spring=None, pull=0.0, obstacle=None):
    """Node 1 resting on the plane z = 0 (or on ``obstacle``, a term on node 1 whose
    surface passes there) under ``force`` (3,), tied to support 0 one metre away by a
    bilateral spring of stiffness ``spring`` (None: a slack tie) that moves ``pull``
    away from it."""
    gap = resting_gap(-force[2])
    tie = dict(EA=spring, tension_only=False) if spring else dict(EA=1.0, rest_length=20.0)
    net = Net.from_arrays(
        [[-1.0, 0, gap], [0.0, 0, gap]], [[0, 1]], fixed=[0], point_mass=[0, mass], **tie
    )
    f = np.zeros((2, 3))
    f[1] = force
    move = np.zeros((2, 3))
    move[0, 0] = -pull
    loads = Loads(force=f, support_displacement=move if pull else None)
    if obstacle is None:
        obstacle = PlaneBarrier(np.array([1]), [0, 0, 0], [0, 0, 1], kappa=KAPPA, dhat=DHAT)
    return Scene(net, loads, (obstacle, Friction(obstacle, mu=mu, slip=slip)))


# --- shapes on a prescribed motion ----------------------------------------------------------

V = [0.3, -0.2, 0.5]
W = [0.4, 1.1, -0.7]


def moving_shapes(dhat=0.05, n=30, history=None):
    nodes = np.arange(n)
    R = rotation([1.0, 2.0, 3.0], 0.7)
    box = BoxBarrier(nodes, [0.1, 0.0, 0.0], [0.5, 0.3, 0.2], R, kappa=30.0, dhat=dhat)
    capsule = CapsuleBarrier(nodes, [0, 0, 0], [1.0, 0.5, 0.0], 0.3, kappa=30.0, dhat=dhat)
    cube = MeshBarrier(nodes, CUBE_V - 0.5, CUBE_T, kappa=30.0, dhat=dhat)
    return {
        "box": Moving(box, [0.1, 0, 0], V, W, history, reach=0.7),
        "capsule": Moving(capsule, [0.5, 0.25, 0], V, W, history, reach=0.9),
        "mesh": Moving(cube, [0, 0, 0], V, W, history, reach=0.9),
    }


def near(term, rng, n, dhat):
    """n points at gaps between 0.05 and 1.4 dhat from the moving term where it is now."""
    out = []
    probe = Moving.__new__(Moving)
    probe.__dict__.update(term.__dict__)
    shape = type(term.shape).__new__(type(term.shape))
    shape.__dict__.update(term.shape.__dict__)
    shape.nodes = np.zeros(1, dtype=np.int64)
    probe.shape, probe.nodes = shape, shape.nodes
    while len(out) < n:
        p = term.world(rng.uniform(-1.2, 1.7, (1, 3)))
        if 0.05 * dhat < probe.gap(p)[0] < 1.4 * dhat:
            out.append(p[0])
    return np.array(out)


# --- scenes as case tables ------------------------------------------------------------------


def flat_case(dhat=0.01, **solver):
    return {
        "title": "a net pressed onto a box",
        "geometry": {"kind": "square_net", "n": 10, "alpha": 0.3, "size": 1.0, "edge_length": 0.05},
        "material": {"E": 10e6, "radius": 0.01, "density": 1000.0},
        "load": {"pressure": 300.0},
        "obstacle": [
            {
                "kind": "box",
                "center": [0.0, 0.0, -0.35],
                "half_size": [0.25, 0.2, 0.3],
                "distance": dhat,
            }
        ],
        "solver": solver or {"method": "static", "steps": 4},
    }


CAPTURE = Path(__file__).parents[1] / "configs" / "contact" / "tether_capture.toml"


def capture_near(dt: float) -> dict:
    """The capture scene with the box (level) 3 mm below the net's middle, which is thrown
    at it too: contact within the first 0.6 ms, so that short runs at every step size
    hit."""
    import tomllib

    from catenet.case import load_case

    data = tomllib.loads(CAPTURE.read_text())
    data["geometry"]["file"] = str(CAPTURE.parent / data["geometry"]["file"])
    box = data["obstacle"][0]
    box["angle"] = 0.0  # its top face level, 3 mm below the middle node
    box.pop("angular_velocity", None)  # and staying so (test_moving_shapes.py tumbles it)
    box["center"] = [0.0, 0.0, -box["half_size"][2] - 0.003]
    data["mass"].append({"node": "middle", "velocity": [0.0, 0.0, -5.0]})
    data["solver"].update(dt=dt, t_end=2 * max(dt, 2e-3))
    data.pop("output")
    assert load_case(CAPTURE).obstacles  # the file itself reads
    return data


G = [0.0, 0.0, -9.81]


def catch_case(coarse: bool = False, **solver) -> dict:
    """The paper's square net (Sec. 3.2, n = 22, alpha = pi/4) and a 10 kg ball of radius
    0.15 m thrown down onto it at 1 m/s from 0.15 m above (configs/contact/sphere_catch.toml
    closer: a ball resting where it cannot roll off, see there). ``coarse``: n = 10 and
    5 cm edges, for runs that need not come to rest."""
    geometry = {"n": 10, "edge_length": 0.05} if coarse else {}
    return {
        "title": "square net catching a ball",
        "geometry": {
            "kind": "square_net",
            "n": 22,
            "alpha": math.pi / 4,
            "size": 1.0,
            "edge_length": 0.02,
            **geometry,
        },
        "material": {"E": 10e6, "radius": 0.01, "density": 1000.0},
        "load": {"gravity": G},
        "obstacle": [
            {
                "kind": "sphere",
                "center": [0.0, 0.0, 0.3],
                "radius": 0.15,
                "mass": 10.0,
                "velocity": [0.0, 0.0, -1.0],
                "distance": 0.005,
            }
        ],
        "solver": {"method": "dynamic", "dt": 0.005, "damping": 0.0, "t_end": 0.4, **solver},
    }


# --- a nylon cord dragged by a box blade round a fixed post (edge contact) ----------------


def dragged_cord(*, nodes, box, half, history, post, t_end, gravity=False, post_half=0.2) -> str:
    """A case: a 2 m nylon cord of 6 mm (EA 70.7 kN, 50 N prestress, pinned ends on x)
    dragged along +y at 0.5 m/s by a box at ``box`` (half sizes ``half``, the speed
    times ``history``) round a fixed capsule post of 20 mm radius whose axis along z
    passes through ``post`` (x, y), with edge contact, at dt = 2 ms."""
    load = "\n[load]\ngravity = [0.0, 0.0, -9.81]\n" if gravity else ""
    return f"""
[geometry]
kind = "cable"
start = [-1.0, 0.0, 0.0]
end = [1.0, 0.0, 0.0]
nodes = {nodes}

[material]
E = 2.5e9
radius = 0.003
density = 1140.0
prestress = 50.0

[[obstacle]]
kind = "box"
center = [{box[0]}, {box[1]}, 0.0]
half_size = [{half[0]}, {half[1]}, {half[2]}]
velocity = [0.0, 0.5, 0.0]
history = {history}

[[obstacle]]
kind = "capsule"
start = [{post[0]}, {post[1]}, {-post_half}]
end = [{post[0]}, {post[1]}, {post_half}]
radius = 0.02
{load}
[solver]
method = "dynamic"
dt = 0.002
t_end = {t_end}
edge_contact = true
"""
