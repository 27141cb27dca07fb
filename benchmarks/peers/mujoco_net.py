"""A cable net and a free box in MuJoCo, set up as its documentation advises: the script
a whole MuJoCo process runs.

    python benchmarks/peers/mujoco_net.py SCENE.json OUT.json [--integrator discrete]
        [--solver Newton] [--dt 0.001] [--noslip 0] [--timed]

SCENE.json is a scene of ``mujoco_scene`` (catenet's net as arrays, the box, the step).
The model (MuJoCo 4.0; the XML reference and the Computation chapter bundled with the
``mujoco`` wheel, ``mujoco/doc``):

- every free node a body with three slide joints along the world axes, its lumped mass,
  and a sphere of the cords' radius that collides with the box only (contype 1,
  conaffinity 0; the box contype 0, conaffinity 1); a fixed node a site of the world;
- every edge a spatial tendon between its two nodes' sites with catenet's law:
  ``stiffness`` EA / r and the dead band ``springlength = "0 r"`` (``mujoco_scene.tendon``).
  MuJoCo 4.0 removed the ``cable`` plugin and the ``composite`` element; their successor,
  the 1D ``flexcomp``, has no stretching ("Stretching is not included; use edge equality
  constraints (or edge stiffness under integrators other than discrete)", XML reference,
  flex/elasticity), its edge stiffness is "integrated explicitly" and neither is
  tension-only. Tendons carry the same law exactly and enter the discrete integrator's
  implicit metric ("joint, tendon and flex stiffness ... are stable at timesteps far
  beyond the explicit stability limit", Computation, Integrators);
- the box a body with a free joint, its mass and inertia, a box geom; friction 0 is
  condim 1 (frictionless), else condim 3 with that Coulomb coefficient; contact solref
  and solimp MuJoCo's defaults;
- ``integrator``: ``discrete`` (the Computation chapter: "Choose discrete when stiff
  springs, position servos or strong damping interact with contacts ... position
  stiffness is unconditionally stable") or ``implicitfast`` ("the recommended
  integrator for most models"; its stiffness is explicit); ``solver`` Newton (the
  default); ``noslip_iterations`` for friction (0: off, the default).

OUT.json: ``finite``, the box's ``momentum`` (T, 3) and ``angular_momentum`` (T, 3, world
frame, about its centre) at the scene's ``samples`` (the step nearest each), ``center``
(T, 3), the deepest ``penetration`` [m] of a node sphere into the box over every step
(MuJoCo's contact distance), ``steps``, ``seconds`` and ``cpu_seconds`` of the stepping
(``--timed``: of a second run that records the samples only, with ``mj_step``'s
``nstep``), ``build_seconds`` and MuJoCo's ``version``.

Imports only NumPy, MuJoCo and ``mujoco_scene``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from mujoco_scene import quaternion, tendon  # noqa: E402

#: A node's rotational inertia [kg m^2]: slide joints carry no rotation; MuJoCo wants it > 0.
TINY_INERTIA = 1e-12
#: A run blows up when a speed exceeds this multiple of the scene's speed scale.
BLOW_UP = 1e3


BIG_MODEL = 2000  # nodes: a model this large is given an arena of 0.1 MB per node


def _f(v) -> str:
    return " ".join(f"{float(x):.17g}" for x in np.ravel(v))


def mjcf(
    scene: dict,
    integrator: str,
    solver: str,
    dt: float,
    noslip: int,
    timeconst: float = 0.0,
    dampratio: float = 1.0,
) -> str:
    """The model's MJCF text; ``timeconst`` > 0: the contacts' solref time constant [s]
    and damping ratio (0: MuJoCo's default, 0.02 s and 1)."""
    nodes = np.asarray(scene["nodes"], float)
    fixed = np.asarray(scene["fixed"], bool)
    mass = np.asarray(scene["mass"], float)
    r = float(scene["radius"])
    box = scene["box"]
    mu = float(box.get("friction", 0.0))
    contact = 'condim="1"' if mu == 0.0 else f'condim="3" friction="{mu:.17g} 0 0"'
    if timeconst > 0:
        contact += f' solref="{timeconst:.17g} {dampratio:.17g}"'
    out = [
        '<mujoco model="catenet net and box">',
        '  <compiler angle="radian" autolimits="true"/>',
        f'  <option timestep="{dt:.17g}" integrator="{integrator}" solver="{solver}" '
        f'gravity="{_f(scene["gravity"])}" noslip_iterations="{int(noslip)}"/>',
        "  <worldbody>",
    ]
    if len(nodes) > BIG_MODEL:  # MuJoCo's default arena (its size/memory) is too small
        out.insert(3, f'  <size memory="{len(nodes) // 10}M"/>')
    for i, p in enumerate(nodes):
        if fixed[i]:
            out.append(f'    <site name="s{i}" pos="{_f(p)}"/>')
            continue
        out += [
            f'    <body name="n{i}" pos="{_f(p)}">',
            f'      <joint name="x{i}" type="slide" axis="1 0 0"/>',
            f'      <joint name="y{i}" type="slide" axis="0 1 0"/>',
            f'      <joint name="z{i}" type="slide" axis="0 0 1"/>',
            f'      <inertial pos="0 0 0" mass="{mass[i]:.17g}" '
            f'diaginertia="{_f([TINY_INERTIA] * 3)}"/>',
            f'      <geom type="sphere" size="{r:.17g}" contype="1" conaffinity="0" {contact}/>',
            f'      <site name="s{i}"/>',
            "    </body>",
        ]
    R = np.asarray(box["axes"], float)
    inertia = np.asarray(box["inertia"], float)
    full = [inertia[i, j] for i, j in ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))]
    out += [
        f'    <body name="box" pos="{_f(box["center"])}" quat="{_f(quaternion(R))}">',
        "      <freejoint/>",
        f'      <inertial pos="0 0 0" mass="{float(box["mass"]):.17g}" fullinertia="{_f(full)}"/>',
        f'      <geom name="box" type="box" size="{_f(box["half_size"])}" contype="0" '
        f'conaffinity="1" {contact}/>',
        "    </body>",
        "  </worldbody>",
        "  <tendon>",
    ]
    for (a, b), EA, rest in zip(scene["edges"], scene["EA"], scene["rest_length"], strict=True):
        if fixed[a] and fixed[b]:
            continue
        t = tendon(float(EA), float(rest))
        out += [
            f'    <spatial stiffness="{t["stiffness"]:.17g}" '
            f'springlength="{_f(t["springlength"])}">',
            f'      <site site="s{a}"/><site site="s{b}"/>',
            "    </spatial>",
        ]
    out += ["  </tendon>", "</mujoco>"]
    return "\n".join(out)


class Run:
    """A MuJoCo model of the scene, ready to step."""

    def __init__(
        self, scene, integrator: str, solver: str, dt: float, noslip: int, timeconst=0.0,
        dampratio=1.0,
    ):  # fmt: skip
        import mujoco

        self.mj = mujoco
        start = time.perf_counter()
        text = mjcf(scene, integrator, solver, dt, noslip, timeconst, dampratio)
        self.model = mujoco.MjModel.from_xml_string(text)
        self.data = mujoco.MjData(self.model)
        self.build_seconds = time.perf_counter() - start
        self.scene, self.dt = scene, dt
        self.box = self.model.body("box").id
        self.box_geom = self.model.geom("box").id
        self.box_joint = self.model.body_jntadr[self.box]
        self.inertia = np.asarray(scene["box"]["inertia"], float)
        self.mass = float(scene["box"]["mass"])
        v = np.asarray(scene["velocity"], float)
        self.speed = max(
            float(np.abs(v).max(initial=0.0)),
            float(np.linalg.norm(scene["box"]["velocity"])),
            float(np.linalg.norm(scene["gravity"])) * float(scene["t_end"]),  # free fall
            1.0,
        )

    def reset(self) -> None:
        m, d, sc = self.model, self.data, self.scene
        self.mj.mj_resetData(m, d)
        v = np.asarray(sc["velocity"], float)
        for i in np.flatnonzero(~np.asarray(sc["fixed"], bool)):
            for k, axis in enumerate("xyz"):
                d.qvel[m.jnt_dofadr[m.joint(f"{axis}{i}").id]] = v[i, k]
        box = sc["box"]
        R = np.asarray(box["axes"], float)
        adr = m.jnt_dofadr[self.box_joint]
        d.qvel[adr : adr + 3] = box["velocity"]
        d.qvel[adr + 3 : adr + 6] = R.T @ np.asarray(box["angular_velocity"], float)  # body frame
        self.mj.mj_forward(m, d)

    def box_state(self):
        """(centre, rotation, momentum, angular momentum about the centre, world)."""
        d = self.data
        adr = self.model.jnt_dofadr[self.box_joint]
        R = d.xmat[self.box].reshape(3, 3)
        v = d.qvel[adr : adr + 3].copy()
        w_body = d.qvel[adr + 3 : adr + 6]
        return d.xpos[self.box].copy(), R.copy(), self.mass * v, R @ (self.inertia @ w_body)

    def deepest(self) -> float:
        """The deepest penetration [m] among the box's contacts now."""
        d = self.data
        if d.ncon == 0:
            return 0.0
        c = d.contact
        mine = (c.geom[:, 0] == self.box_geom) | (c.geom[:, 1] == self.box_geom)
        return float(max(0.0, -c.dist[mine].min())) if mine.any() else 0.0

    def go(self, samples, watch: bool = True) -> dict:
        """Steps to the last sample; the box's state at every sample."""
        self.reset()
        targets = [max(0, round(float(t) / self.dt)) for t in samples]
        rec = {"momentum": [], "angular_momentum": [], "center": [], "time": []}
        deepest, step, finite = 0.0, 0, True
        limit = BLOW_UP * self.speed
        t0, c0 = time.perf_counter(), time.process_time()
        for target in targets:
            while step < target and finite:
                if watch:
                    self.mj.mj_step(self.model, self.data)
                    deepest = max(deepest, self.deepest())
                    step += 1
                else:
                    self.mj.mj_step(self.model, self.data, target - step)
                    step = target
                qvel = self.data.qvel
                # the speeds of the nodes and the box (its spin, the last three, is not one)
                finite = bool(np.isfinite(qvel).all()) and float(np.abs(qvel[:-3]).max()) < limit
            c, _, p, L = self.box_state()
            rec["center"].append(c.tolist())
            rec["momentum"].append(p.tolist())
            rec["angular_momentum"].append(L.tolist())
            rec["time"].append(step * self.dt)
        seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
        finite = finite and all(np.isfinite(rec["momentum"][-1]))
        # MuJoCo resets a run that blew up (its bad-acceleration warning) and goes on
        finite = finite and self.data.warning[self.mj.mjtWarning.mjWARN_BADQACC].number == 0
        return {
            **rec,
            "finite": bool(finite),
            "penetration": deepest if watch else None,
            "steps": step,
            "seconds": seconds,
            "cpu_seconds": cpu,
        }


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene")
    parser.add_argument("out")
    parser.add_argument("--integrator", default="discrete")
    parser.add_argument("--solver", default="Newton")
    parser.add_argument("--dt", type=float, default=None, help="default: the scene's")
    parser.add_argument("--noslip", type=int, default=0)
    parser.add_argument("--timeconst", type=float, default=0.0, help="contact solref [s]")
    parser.add_argument("--dampratio", type=float, default=1.0, help="contact solref")
    parser.add_argument("--timed", action="store_true", help="time a second, unwatched run")
    args = parser.parse_args(argv)
    import mujoco

    scene = json.loads(Path(args.scene).read_text())
    dt = float(args.dt if args.dt is not None else scene["dt"])
    run = Run(scene, args.integrator, args.solver, dt, args.noslip, args.timeconst, args.dampratio)
    out = run.go(scene["samples"])
    if args.timed and out["finite"]:
        timed = run.go(scene["samples"], watch=False)
        out["seconds"], out["cpu_seconds"] = timed["seconds"], timed["cpu_seconds"]
        out["timed_momentum"] = timed["momentum"][-1]
    out.update(
        build_seconds=run.build_seconds,
        version=mujoco.__version__,
        integrator=args.integrator,
        solver=args.solver,
        dt=dt,
        noslip=args.noslip,
        timeconst=args.timeconst,
        dampratio=args.dampratio,
        nv=int(run.model.nv),
        ntendon=int(run.model.ntendon),
    )
    Path(args.out).write_text(json.dumps(out))


if __name__ == "__main__":
    main()
