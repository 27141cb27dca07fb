"""catenet against MoorDyn (v2, its Python package) on three mooring lines: a catenary
chain on the seabed under a surge sine at its fairlead, a taut synthetic line under a
heave sine, and the chain in a crossflow current under the same surge.

Both models are set up alike where they can be: the same line (mass per length, EA,
volume-equivalent diameter for buoyancy and drag), the same drag law (Morison, cd_n on
d l, cd_t on pi d l), the same added mass (ca_n, ca_t), the same number of segments,
water density, gravity and depth, the same fairlead motion (a sine started smoothly over
one period, its exact velocity given to MoorDyn) and both starting from the line's
static equilibrium (catenet: ``solver.initial_state = "equilibrium"``; MoorDyn: its
initial-condition solver). They differ where the methods do: MoorDyn's seabed is a
spring-damper (kBot, cBot) the line sinks into, catenet's a barrier it never crosses;
MoorDyn adds internal axial damping (BA/-zeta, -1 here: critical for each segment's axial
mode, as its documentation's examples set it); MoorDyn integrates explicitly (RK2, its
default, at the step its CFL number allows), catenet implicitly (implicit Euler at dt).

    python benchmarks/peers/moordyn_lines.py            # the comparison, then speed
    python benchmarks/peers/moordyn_lines.py --quick    # shorter runs (the test's)

(``pip install moordyn``.) Prints, per line: the static fairlead tension of each and
their difference; the dynamic fairlead tension histories' largest difference over the
run relative to the peak, and the peaks; the CPU time per simulated second of each
engine (the solve alone) and of each whole process (start-up, input, solve, exit).
"""

from __future__ import annotations

import contextlib
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, replace
from pathlib import Path

if __name__ == "__main__":  # one thread (set before NumPy, MKL and Numba load; never on
    # import: a test process's threads are set already)
    for _k in ("MKL_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
        os.environ.setdefault(_k, "1")

import numpy as np  # noqa: E402

RHO_W, G = 1025.0, 9.81
SETTLE = 1200.0  # s: MoorDyn held at rest after its initial-condition solve, at most
BA = -1.0  # MoorDyn's internal axial damping: -zeta, a fraction of each segment's critical


@dataclass(frozen=True)
class Line:
    """A mooring line between an anchor and a fairlead moved by a sine."""

    name: str
    anchor: tuple[float, float, float]
    fairlead: tuple[float, float, float]
    length: float  # unstretched [m]
    segments: int
    diameter: float  # volume-equivalent [m]: buoyancy, drag, added mass
    mass: float  # [kg/m]
    EA: float
    cd_n: float
    cd_t: float
    ca_n: float
    ca_t: float
    depth: float
    amplitude: tuple[float, float, float]  # the fairlead's sine [m]
    period: float
    current: float = 0.0  # uniform, along +y [m/s]
    guess: tuple = ()  # catenet's starting polyline (nodes between anchor and fairlead)
    edge_length: float = 0.0  # catenet's longest edge along the guess (0: length / segments)

    @property
    def area(self) -> float:
        return 0.25 * math.pi * self.diameter**2


# The chain of configs/water/mooring_surge.toml: 800 m (its 84 edges) of 81 mm studless chain (1.8 d
# volume-equivalent diameter 0.146 m, 132.3 kg/m), 100 m of water, fairlead 10 m down.
CHAIN = Line(
    "catenary chain, surge +-5 m at 12 s",
    (-762.419, 0.0, -100.0),
    (0.0, 0.0, -10.0),
    799.806,  # the polyline's length (configs/water/mooring_surge.toml's)
    84,
    0.146,
    132.28,
    5e8,
    1.33,
    0.64,
    1.0,
    0.5,
    100.0,
    (5.0, 0.0, 0.0),
    12.0,
    guess=(
        (-117.517, 0.0, -99.995),
        (-97.931, 0.0, -97.822),
        (-78.345, 0.0, -91.198),
        (-58.758, 0.0, -79.796),
        (-39.172, 0.0, -63.059),
        (-19.586, 0.0, -40.166),
    ),
    edge_length=10.0,
)
# A taut polyester leg: 160 mm rope, EA 80 MN, 120 m long on a 120.4 m chord (about
# 280 kN of pretension), from the seabed 100 m down to a fairlead 10 m down.
TAUT = Line(
    "taut polyester line, heave +-0.3 m at 10 s",
    (-80.0, 0.0, -100.0),
    (0.0, 0.0, -10.0),
    120.0,
    40,
    0.16,
    27.75,
    8e7,
    1.2,
    0.008,
    1.0,
    0.0,
    100.0,
    (0.0, 0.0, 0.3),
    10.0,
)
CURRENT = replace(CHAIN, name="catenary chain in a 1 m/s crossflow current, surge", current=1.0)
LINES = (CHAIN, TAUT, CURRENT)


def sine(line: Line, t: float) -> tuple[np.ndarray, np.ndarray]:
    """The fairlead's displacement and velocity at t: catenet's sine with its default
    ramp (one period): A r(t) sin(w t), r = (1 - cos(pi t / T)) / 2 over the first T."""
    w, T = 2 * math.pi / line.period, line.period
    s, c = math.sin(w * t), math.cos(w * t)
    if t < T:
        r, dr = 0.5 * (1 - math.cos(math.pi * t / T)), 0.5 * math.pi / T * math.sin(math.pi * t / T)
    else:
        r, dr = 1.0, 0.0
    a = np.array(line.amplitude)
    return a * r * s, a * (dr * s + r * w * c)


# --------------------------------------------------------------------------- catenet


def catenet_case(line: Line, t_end: float, dt: float) -> dict:
    nodes = [list(line.anchor), *[list(p) for p in line.guess], list(line.fairlead)]
    case = {
        "geometry": {
            "kind": "graph",
            "nodes": nodes,
            "edge_length": line.edge_length or line.length / line.segments,
            "sets": {"anchor": [0], "fairlead": [len(nodes) - 1]},
            "cable": [{"name": "line", "nodes": list(range(len(nodes)))}],
        },
        "supports": {
            "fixed": ["anchor", "fairlead"],
            "move": [
                {
                    "node": "fairlead",
                    "sine": {"amplitude": list(line.amplitude), "period": line.period},
                }
            ],
        },
        "material": {
            "EA": line.EA,
            "area": line.area,
            "density": line.mass / line.area,
            "hydro_diameter": line.diameter,
            "cd_n": line.cd_n,
            "cd_t": line.cd_t,
            "ca_n": line.ca_n,
            "ca_t": line.ca_t,
        },
        "water": {"density": RHO_W, "depth": line.depth},
        "load": {"gravity": [0.0, 0.0, -G]},
        "obstacle": [
            {
                "kind": "plane",
                "point": [0.0, 0.0, -line.depth],
                "normal": [0.0, 0.0, 1.0],
                "distance": 0.01,
            }
        ],
        "solver": {
            "method": "dynamic",
            "initial_state": "equilibrium",
            "dt": dt,
            "t_end": t_end,
        },
    }
    if not line.guess:  # a straight start: the line's own length, in equal edges
        chord = math.dist(line.anchor, line.fairlead)
        case["geometry"]["edge_length"] = chord / line.segments * (1 + 1e-9)
        case["geometry"]["cable"][0]["rest_length"] = [line.length / line.segments] * line.segments
    if line.current:
        case["water"]["current"] = [[-line.depth, 0.0, line.current], [0.0, 0.0, line.current]]
    return case


def run_catenet(line: Line, t_end: float, dt: float) -> dict:
    """catenet in this process: the fairlead tension at every step, the static one, the
    CPU time of the solve."""
    from catenet.case import parse_case
    from catenet.case.scene import build
    from catenet.solver.path import Settings, solve

    case = parse_case(catenet_case(line, t_end, dt))
    scene = build(case)
    net = scene.net
    top = int(np.flatnonzero(net.edges == len(line.guess) + 1)[0] // 2)  # the fairlead's edge
    i, j = net.edges[top]
    rows = []

    def seen(st) -> None:
        length = np.linalg.norm(st.x[j] - st.x[i])
        rows.append((st.time, net.EA[top] * (length / net.rest_length[top] - 1.0)))

    cpu = time.process_time()
    solve(scene, Settings.of(case.solver), on_step=seen)
    cpu = time.process_time() - cpu
    t, ten = np.array(rows).T
    return {"t": t, "tension": ten, "static": float(ten[0]), "cpu": cpu}


# --------------------------------------------------------------------------- MoorDyn


def moordyn_input(line: Line, folder: Path, dtm: float) -> Path:
    """MoorDyn's input file of the line (and its current profile), as its docs set one."""
    a, f = line.anchor, line.fairlead
    hydro_t = f"{line.cd_t}  {line.ca_t}"
    text = f"""--------------------- MoorDyn Input File ------------------------------------
{line.name}
----------------------- LINE TYPES ------------------------------------------
TypeName   Diam    Mass/m     EA         BA/-zeta    EI    Cd     Ca     CdAx    CaAx
(name)     (m)     (kg/m)     (N)        (N-s/-)     (N-m^2) (-)  (-)    (-)     (-)
line  {line.diameter}  {line.mass}  {line.EA}  {BA}  0  {line.cd_n}  {line.ca_n}  {hydro_t}
---------------------- POINTS --------------------------------
ID    Attachment  X       Y       Z       Mass   Volume  CdA    Ca
(#)   (-)         (m)     (m)     (m)     (kg)   (m^3)   (m^2)  (-)
1     Fixed       {a[0]}  {a[1]}  {a[2]}  0      0       0      0
2     Coupled     {f[0]}  {f[1]}  {f[2]}  0      0       0      0
---------------------- LINES ----------------------------------------
ID   LineType   AttachA  AttachB  UnstrLen  NumSegs  Outputs
(#)  (name)     (#)      (#)      (m)       (-)      (-)
1    line       1        2        {line.length}  {line.segments}  -
---------------------- OPTIONS -----------------------------------------
{dtm}        dtM          time step to use in mooring integration (s)
{G}          g            gravity (m/s^2)
{RHO_W}      rho          water density (kg/m^3)
{line.depth} WtrDpth      water depth (m)
3.0e6        kBot         bottom stiffness (Pa/m)
3.0e5        cBot         bottom damping (Pa-s/m)
1.0e-5       threshIC     threshold for IC convergence (-)
300          TmaxIC       max time for IC generation (s)
{1 if line.current else 0}  Currents  steady currents from current_profile.txt
1            disableOutput
1            disableOutTime
------------------------- need this line --------------------------------------
"""
    path = folder / "lines.txt"
    path.write_text(text)
    if line.current:
        rows = "\n".join(f"{z:.1f} 0.0 {line.current} 0.0" for z in (-line.depth - 1, 0.0, 1.0))
        (folder / "current_profile.txt").write_text(
            "--- MoorDyn steady currents File ---\nTabulated currents\n"
            f"z (m), ux (m/s), uy (m/s), uz (m/s)\n{rows}\n"
        )
    return path


@contextlib.contextmanager
def quiet():
    """Standard output (of the C++ library too) to /dev/null."""
    sys.stdout.flush()
    saved = os.dup(1)
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, 1)
    try:
        yield
    finally:
        os.dup2(saved, 1)
        os.close(null)
        os.close(saved)


def settle(moordyn, system, ml, x0: list, chunk: float = 0.5) -> float:
    """Holds MoorDyn's line still after its initial-condition solve (which stops short
    of rest, and leaves a current out) until its fairlead tension changes by less than
    1e-5 over 10 s (at most SETTLE s); the time held."""
    t, last = 0.0, moordyn.GetLineFairTen(ml)
    while t < SETTLE:
        for _ in range(int(round(10.0 / chunk))):
            moordyn.Step(system, x0, [0.0, 0.0, 0.0], t, chunk)
            t += chunk
        now = moordyn.GetLineFairTen(ml)
        if abs(now - last) <= 1e-5 * abs(now):
            break
        last = now
    return t


def run_moordyn(line: Line, t_end: float, dt: float, dtm: float = 1e-3) -> dict:
    """MoorDyn in this process, coupled at dt: the fairlead tension at every coupling
    step, the static one after its initial-condition solve, the CPU time of the solve."""
    import moordyn

    with tempfile.TemporaryDirectory() as tmp:
        path = moordyn_input(line, Path(tmp), dtm)
        cwd = os.getcwd()
        os.chdir(tmp)  # the current profile is read from beside the input file
        try:
            cpu = time.process_time()
            x0 = np.array(line.fairlead)
            with quiet():  # its console report of the input and the IC solve
                system = moordyn.Create(str(path))
                moordyn.Init(system, list(x0), [0.0, 0.0, 0.0])
            ml = moordyn.GetLine(system, 1)
            first = moordyn.GetLineFairTen(ml)
            held = settle(moordyn, system, ml, list(x0))
            ic = time.process_time() - cpu
            cpu = time.process_time()
            rows = [(0.0, moordyn.GetLineFairTen(ml), top_segment(moordyn, ml, line))]
            n = int(round(t_end / dt))
            for k in range(n):
                t = (k + 1) * dt
                d, v = sine(line, t)
                moordyn.Step(system, list(x0 + d), list(v), held + k * dt, dt)
                rows.append((t, moordyn.GetLineFairTen(ml), top_segment(moordyn, ml, line)))
            cpu = time.process_time() - cpu
            step = dtm
            moordyn.Close(system)
        finally:
            os.chdir(cwd)
    t, node, ten = np.array(rows).T
    out = {"t": t, "tension": ten, "static": float(ten[0]), "cpu": cpu, "ic": ic, "dtM": step}
    return out | {"ic_tension": first, "held": held, "fairlead_node": node}


def top_segment(moordyn, ml, line: Line) -> float:
    """The elastic tension EA (l / l0 - 1) of MoorDyn's segment at the fairlead: the
    quantity catenet's fairlead edge gives. (MoorDyn's own GetLineFairTen is the net
    force on its fairlead node less that node's mass times g: it adds the node's half
    segment of drag and buoyancy and the segment's internal damping, and takes the
    added mass for mass in the weight.)"""
    n = moordyn.GetLineN(ml)
    a = np.asarray(moordyn.GetLineNodePos(ml, n - 1))
    b = np.asarray(moordyn.GetLineNodePos(ml, n))
    return line.EA * (float(np.linalg.norm(b - a)) / (line.length / n) - 1.0)


# --------------------------------------------------------------------------- compare


def compare(line: Line, t_end: float, dt: float = 0.05) -> dict:
    """Both tools' fairlead tension histories on the coupling grid of dt."""
    cat = run_catenet(line, t_end, dt)
    md = run_moordyn(line, t_end, dt)
    on = np.interp(md["t"], cat["t"], cat["tension"])
    peak = max(md["tension"].max(), cat["tension"].max())
    return {
        "line": line.name,
        "static": (cat["static"], md["static"]),
        "peak": (cat["tension"].max(), md["tension"].max()),
        "least": (cat["tension"].min(), md["tension"].min()),
        "largest difference": float(np.abs(on - md["tension"]).max() / peak),
        "rms difference": float(np.sqrt(np.mean((on - md["tension"]) ** 2)) / peak),
        "cpu": (cat["cpu"], md["cpu"]),
        "ic_tension": md["ic_tension"],
        "held": md["held"],
        "dtM": md["dtM"],
        "t": md["t"],
        "catenet": on,
        "moordyn": md["tension"],
        "moordyn_fairlead_node": md["fairlead_node"],
    }


def whole_process(tool: str, k: int, t_end: float) -> float:
    """CPU seconds (user + system) of a whole process running one line's dynamic run."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    here = str(Path(__file__).parent)
    code = f"import sys; sys.path.insert(0, {here!r}); import moordyn_lines as m; "
    code += f"m.run_{tool}(m.LINES[{k}], {t_end}, 0.05)"
    subprocess.run([sys.executable, "-c", code], check=True, capture_output=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def accuracy(line: Line, t_end: float) -> None:
    """Each tool's peak fairlead tension and engine CPU per simulated second as its step
    halves: the step at which each is converged to 1 %."""
    for dt in (0.1, 0.05, 0.025):
        r = run_catenet(line, t_end, dt)
        print(
            f"  catenet dt {dt:g} s: peak {r['tension'].max() / 1e3:.2f} kN, "
            f"CPU {r['cpu'] / t_end:.3f} s per simulated s"
        )
    for dtm in (4e-3, 2e-3, 1e-3, 5e-4):
        try:
            r = run_moordyn(line, t_end, 0.05, dtm)
        except RuntimeError as exc:  # an explicit step beyond its stability limit
            print(f"  MoorDyn dtM {dtm:g} s: {exc}")
            continue
        print(
            f"  MoorDyn dtM {dtm:g} s: peak {r['tension'].max() / 1e3:.2f} kN, "
            f"CPU {r['cpu'] / t_end:.3f} s per simulated s"
        )


def main() -> None:
    quick = "--quick" in sys.argv
    t_end = 15.0 if quick else 36.0
    print(f"t_end = {t_end} s; fairlead tension [kN]; differences relative to the peak")
    for k, line in enumerate(LINES):
        r = compare(line, t_end)
        cs, ms = r["static"]
        print(f"\n{line.name}")
        print(
            f"  static: catenet {cs / 1e3:.2f}, MoorDyn {ms / 1e3:.2f} ({(cs - ms) / ms:+.2%}; "
            f"after its IC solve {r['ic_tension'] / 1e3:.2f}, at rest after {r['held']:.0f} s)"
        )
        cp, mp = r["peak"]
        cl, ml = r["least"]
        print(f"  peak:   catenet {cp / 1e3:.2f}, MoorDyn {mp / 1e3:.2f} ({(cp - mp) / mp:+.2%})")
        print(f"  least:  catenet {cl / 1e3:.2f}, MoorDyn {ml / 1e3:.2f}")
        print(
            f"  history: largest difference {r['largest difference']:.2%}, "
            f"rms {r['rms difference']:.2%}"
        )
        cc, mc = r["cpu"]
        print(
            f"  engine CPU per simulated s: catenet {cc / t_end:.3f} s (dt 0.05 s), "
            f"MoorDyn {mc / t_end:.3f} s (dtM {r['dtM']:.2e} s)"
        )
        if not quick:
            wc, wm = whole_process("catenet", k, t_end), whole_process("moordyn", k, t_end)
            print(
                f"  whole process CPU: catenet {wc:.2f} s, MoorDyn {wm:.2f} s (its IC solve "
                "and the hold to rest included)"
            )
    if not quick:
        for line in (CHAIN, TAUT):
            print(f"\nconvergence in the step, {line.name}")
            accuracy(line, t_end)


if __name__ == "__main__":
    main()
