"""The time integrators: implicit Euler (first order, the paper's), newmark (second
order, Bossak's high-frequency dissipation rho_inf) and bdf2 (second order, L-stable):
order of convergence against a fine reference and against the closed form of a mass on a
spring, the energy of undamped runs, restarts, the case keys, and mu's effect on the
settling time."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import h5py
import numpy as np
import pytest
from conftest import CONFIGS

import catenet as cn
from catenet.case.parse import parse_case
from catenet.case.scene import build
from catenet.errors import ConfigError
from catenet.run import advice
from catenet.run.runner import run_case
from catenet.solver.dynamic import solve_dynamic
from catenet.solver.integrators import RHO_INF, make
from catenet.solver.path import Settings, Start, solve
from catenet.solver.spectral import amplification, numerical_damping
from catenet.solver.static import Workspace

# --------------------------------------------------------------------------- scenes


def string(n: int = 11, speed: float = 3.0):
    """A pretensioned string (1 % strain, lowest transverse mode omega ~ 100 1/s) under
    gravity, started with the velocity of its first mode, speed * sin(pi x)."""
    s = np.linspace(0.0, 1.0, n)
    nodes = np.c_[s, 0 * s, 0 * s]
    edges = np.c_[np.arange(n - 1), np.arange(1, n)]
    net = cn.Net.from_arrays(
        nodes, edges, EA=1e4, fixed=[0, n - 1], rest_length=0.99 / (n - 1), line_density=0.1
    )
    v0 = np.zeros_like(nodes)
    v0[:, 2] = speed * np.sin(np.pi * s)
    return net, cn.Loads(gravity=np.array([0.0, 0.0, -9.81])), v0


def string_run(integrator, dt, t_end, *, damping=0.0, rho_inf=1.0, on_step=None, **kw):
    net, loads, v0 = string()
    return solve_dynamic(
        net,
        loads,
        dt=dt,
        damping=damping,
        t_end=t_end,
        rtol=1e-12,
        v0=kw.pop("v0", v0),
        stop_at_equilibrium=False,
        integrator=integrator,
        rho_inf=rho_inf,
        on_step=on_step,
        **kw,
    )


def net_on_plane(dt: float, integrator: str, rho_inf: float = RHO_INF) -> dict:
    """A small square net (n = 4) falling under its weight onto a ground plane whose
    barrier acts from the start (damping 2 1/s)."""
    return {
        "geometry": {"kind": "square_net", "n": 4, "alpha": 0.0, "size": 1.0, "edge_length": 0.05},
        "material": {"E": 10e6, "radius": 0.01, "density": 1000.0},
        "load": {"gravity": [0, 0, -9.81]},
        "obstacle": [{"kind": "plane", "point": [0, 0, -0.01], "normal": [0, 0, 1],
                      "distance": 0.02}],
        "solver": {"method": "dynamic", "dt": dt, "damping": 2.0, "t_end": 0.1, "rtol": 1e-10,
                   "integrator": integrator}
        | ({"rho_inf": rho_inf} if integrator == "newmark" else {}),
    }  # fmt: skip


def plane_run(dt, integrator, rho_inf=RHO_INF):
    scene = build(parse_case(net_on_plane(dt, integrator, rho_inf)))
    plane = scene.terms[0]
    gaps = []
    r = solve(
        scene,
        Settings.of(scene.case.solver),
        on_step=lambda s: gaps.append(float(plane.gap(s.x).min())),
    )
    assert r.converged and min(gaps) > 0.0
    assert min(gaps) < plane.dhat  # in contact
    return r.x


def ratios(errors):
    return [errors[k] / errors[k + 1] for k in range(len(errors) - 1)]


# --------------------------------------------------------------------------- order


ORDERS = [("implicit_euler", 1.6, 2.4), ("newmark", 3.3, 4.7), ("bdf2", 3.3, 4.7)]


@pytest.mark.parametrize("integrator, low, high", ORDERS)
def test_order_of_convergence_on_a_string(integrator, low, high):
    """Errors at h, h/2, h/4 against newmark at h/40: ratios about 2 (implicit Euler) and
    about 4 (newmark, with its default rho_inf, and bdf2)."""
    ref = string_run("newmark", 2.5e-5, 0.06).x
    errors = [
        np.abs(string_run(integrator, dt, 0.06, rho_inf=RHO_INF).x - ref).max()
        for dt in (1e-3, 5e-4, 2.5e-4)
    ]
    assert all(low < q < high for q in ratios(errors)), errors


@pytest.mark.parametrize("integrator, low, high", [o for o in ORDERS if o[0] != "newmark"])
def test_order_of_convergence_in_contact_with_a_plane(integrator, low, high):
    """The same scene with a fixed obstacle, damped (mu = 2): implicit Euler converges at
    first order, bdf2 at second (the damping enters at second order), every node outside
    the plane at every step (newmark is refused in contact)."""
    ref = plane_run(5e-5, "bdf2")
    errors = [np.abs(plane_run(dt, integrator) - ref).max() for dt in (1e-3, 5e-4, 2.5e-4)]
    assert all(low < q < high for q in ratios(errors)), errors


def spring_error(integrator: str, dt: float, t_end: float = 0.5) -> float:
    """|x - x_exact| at t_end of a mass on an axial spring: one edge (EA = 100 N, l0 = 1 m)
    from a support to a 1 kg point mass, held at 2 % strain by a 2 N force and released
    from 3 %: x(t) = 1.02 + 0.01 cos(10 t) while the edge stays taut (it does)."""
    nodes = np.array([[0.0, 0.0, 0.0], [1.03, 0.0, 0.0]])
    net = cn.Net.from_arrays(
        nodes, [[0, 1]], EA=100.0, fixed=[0], rest_length=1.0, point_mass=[0.0, 1.0]
    )
    loads = cn.Loads(force=np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]]))
    r = solve_dynamic(
        net, loads, dt=dt, damping=0.0, t_end=t_end, rtol=1e-12, stop_at_equilibrium=False,
        integrator=integrator,
    )  # fmt: skip
    assert r.converged and r.time == pytest.approx(t_end)
    return abs(r.x[1, 0] - (1.02 + 0.01 * math.cos(10.0 * t_end)))


@pytest.mark.parametrize("integrator, low, high", ORDERS)
def test_order_against_the_closed_form_of_a_mass_on_a_spring(integrator, low, high):
    """Five periods of 0.63 s at h = 10, 5 and 2.5 ms: the error against the closed form
    falls 2x per halving (implicit Euler) and 4x (newmark, bdf2)."""
    errors = [spring_error(integrator, dt) for dt in (1e-2, 5e-3, 2.5e-3)]
    assert all(low < q < high for q in ratios(errors)), errors
    assert errors[-1] < (2e-4 if integrator == "implicit_euler" else 2e-5)


# --------------------------------------------------------------------------- energy


def energies(integrator, dt, t_end, rho_inf):
    """Kinetic + strain energy - work of the (constant) gravity at every step."""
    net, loads, v0 = string()
    ws = Workspace(net)
    f = loads.external_force(net)
    mass = net.mass[:, None]

    def total(x, v):
        return 0.5 * float(np.sum(mass * v * v)) + ws.system.gradient(x)[0] - float(np.sum(f * x))

    out = [total(net.nodes, v0)]
    string_run(
        integrator,
        dt,
        t_end,
        rho_inf=rho_inf,
        workspace=ws,
        on_step=lambda k, t, x, v: out.append(total(x, v)),
    )
    return np.array(out)


def test_undamped_energy_error_is_second_order():
    """mu = 0: average acceleration (rho_inf = 1) keeps the energy within O(h^2) of its
    start over 8 periods (ratio about 4 from h to h/2); the default rho_inf loses at
    least as little as O(h^2) (its dissipation of a resolved mode is O(h^3)), and
    implicit Euler loses most of it."""
    net, _, v0 = string()
    kinetic = 0.5 * float(np.sum(net.mass[:, None] * v0 * v0))  # the motion's energy
    e0 = energies("newmark", 4e-3, 0.5, 1.0)[0]
    for rho_inf, low, high in ((1.0, 3.3, 4.7), (RHO_INF, 3.3, 16.0)):
        drift = [
            np.abs(energies("newmark", dt, 0.5, rho_inf) - e0).max() for dt in (4e-3, 2e-3, 1e-3)
        ]
        assert all(low < q < high for q in ratios(drift)), (rho_inf, drift)
        assert drift[2] < 0.02 * kinetic
    euler = energies("implicit_euler", 4e-3, 0.5, 1.0)
    assert e0 - euler[-1] > 0.8 * kinetic  # numerical damping: most of the motion gone


# --------------------------------------------------------------------------- spectra


def test_spectral_properties():
    """rho_inf is the spectral radius far beyond the resolved modes; average
    acceleration damps nothing; implicit Euler damps a mode at h omega by about
    h omega / 2 of critical."""
    for rho in (0.5, 0.8, 1.0):
        big = np.abs(np.linalg.eigvals(amplification("newmark", 1e6, 0.0, rho))).max()
        assert big == pytest.approx(rho, abs=1e-4)
    assert abs(numerical_damping("newmark", 0.5, 1.0)[0]) < 1e-12
    small = [numerical_damping("newmark", s, 0.9)[0] for s in (0.2, 0.1)]
    assert small[0] / small[1] == pytest.approx(8.0, rel=0.1)  # O((h omega)^3)
    assert numerical_damping("implicit_euler", 0.01)[0] == pytest.approx(0.005, rel=1e-3)
    # A linear oscillator integrated by the solver decays as the analysis says.
    for name in ("implicit_euler", "newmark"):
        m = amplification(name, 0.3, 0.05, 0.8)
        assert np.abs(np.linalg.eigvals(m)).max() < 1.0


# --------------------------------------------------------------------------- restart


def test_a_restart_repeats_the_uninterrupted_run():
    """Going on from the scheme's whole state (x, v and its acceleration a) repeats the
    uninterrupted run to round-off, also with rho_inf < 1, where a is a filtered
    acceleration. Without a (a file that does not store it) the restart starts from the
    physical acceleration: exact for average acceleration, and with rho_inf < 1 a
    transient within the discretisation error (h against h/2)."""
    for rho_inf in (1.0, RHO_INF):
        whole = string_run("newmark", 1e-3, 0.1, rho_inf=rho_inf)
        half = string_run("newmark", 1e-3, 0.05, rho_inf=rho_inf)
        assert half.a.shape == half.x.shape and np.all(half.a[[0, -1]] == 0.0)
        moved = np.abs(whole.x - string()[0].nodes).max()
        state = {"x0": half.x, "v0": half.v, "t0": half.time}
        exact = string_run("newmark", 1e-3, 0.1, rho_inf=rho_inf, a0=half.a, **state)
        assert exact.time == whole.time and exact.steps == half.steps == 50
        assert np.abs(exact.x - whole.x).max() <= 1e-12 * moved
        np.testing.assert_allclose(exact.a, whole.a, rtol=0, atol=1e-9 * np.abs(whole.a).max())
        rest = string_run("newmark", 1e-3, 0.1, rho_inf=rho_inf, **state)
        assert rest.time == whole.time and rest.steps == half.steps == 50
        off = np.abs(rest.x - whole.x).max()
        if rho_inf == 1.0:
            assert off < 1e-12 * moved
        else:  # well within the discretisation error (h against h/2)
            finer = string_run("newmark", 5e-4, 0.1, rho_inf=rho_inf)
            assert 1e-9 * moved < off < 0.2 * np.abs(finer.x - whole.x).max()
    euler = string_run("implicit_euler", 1e-3, 0.01, a0=np.ones_like(whole.x))
    assert euler.a is None  # implicit Euler has no acceleration state
    with pytest.raises(ConfigError, match=r"a0: must have shape \(11, 3\)"):
        string_run("newmark", 1e-3, 0.01, a0=np.zeros(3))


def cable_case(t_end: float, **solver) -> dict:
    return {
        "geometry": {"kind": "cable", "start": [0, 0, 0], "end": [1, 0, 0], "nodes": 11,
                     "length": 0.99},
        "material": {"E": 10e6, "radius": 0.01, "density": 1000.0},
        "load": {"gravity": [0, 0, -9.81]},
        "mass": [{"node": "midpoint", "mass": 0.05, "velocity": [0, 0, 1.0]}],
        "solver": {"method": "dynamic", "dt": 0.005, "damping": 0.5, "t_end": t_end,
                   "integrator": "newmark", "rho_inf": 1.0, "rtol": 1e-10, **solver},
        "output": {"every": 5},
    }  # fmt: skip


def test_runner_restart_and_velocities_of_a_newmark_case(tmp_path):
    """A TOML case with a point mass and its initial velocity runs with newmark; a run
    restarted from the file of its first half (catenet run --restart) ends where the
    uninterrupted one does."""
    whole = run_case(parse_case(cable_case(0.2)), tmp_path / "whole.h5")
    first = run_case(parse_case(cable_case(0.1)), tmp_path / "first.h5")
    second = run_case(
        parse_case(cable_case(0.2)), tmp_path / "second.h5", restart=tmp_path / "first.h5"
    )
    assert whole.time == second.time == pytest.approx(0.2)
    assert first.time == pytest.approx(0.1)
    moved = np.abs(whole.x[:, 2]).max()
    assert moved > 1e-3
    assert np.abs(second.x - whole.x).max() < 1e-8 * moved + 1e-12
    assert np.abs(second.v - whole.v).max() < 1e-6 * np.abs(whole.v).max()
    with h5py.File(tmp_path / "whole.h5", "r") as h5:  # the resolved case names the scheme
        solver = tomllib.loads(h5.attrs["case"])["solver"]
    assert (solver["integrator"], solver["rho_inf"]) == ("newmark", 1.0)


def test_catenet_run_restart_of_a_dissipative_newmark_run_is_exact(tmp_path):
    """With rho_inf < 1 the result file keeps the scheme's acceleration state with every
    frame and /result (/trajectory/a, /result/a), and `catenet run --restart` goes on
    from it: the restarted run repeats the uninterrupted one to round-off. A file without
    it (an older one) restarts from the physical acceleration, as before; implicit Euler
    files do not store it."""
    from click.testing import CliRunner

    from catenet.cli import main
    from catenet.output import read_frame
    from catenet.output.repair import recover

    case = tmp_path / "case.toml"
    case.write_text(parse_case(cable_case(0.2, rho_inf=0.8)).to_toml())

    def run(*args):
        r = CliRunner().invoke(main, ["run", str(case), *map(str, args)])
        assert r.exit_code == 0, r.output
        with h5py.File(args[1], "r") as h5:
            return {k: h5[f"result/{k}"][()] for k in ("x", "v", "a") if k in h5["result"]}

    whole = run("-o", tmp_path / "whole.h5")
    run("-o", tmp_path / "first.h5", "--set", "solver.t_end=0.1")
    second = run("-o", tmp_path / "second.h5", "--restart", tmp_path / "first.h5")
    moved = np.abs(whole["x"][:, 2]).max()
    assert moved > 1e-3
    assert np.abs(second["x"] - whole["x"]).max() <= 1e-12 * moved
    assert np.abs(second["v"] - whole["v"]).max() <= 1e-12 * np.abs(whole["v"]).max()
    assert np.abs(second["a"] - whole["a"]).max() <= 1e-9 * np.abs(whole["a"]).max()

    first = read_frame(tmp_path / "first.h5")
    with h5py.File(tmp_path / "first.h5", "r") as h5:
        frames = h5["trajectory/a"][()]
        fixed = h5["mesh/fixed"][()]
        np.testing.assert_array_equal(h5["result/a"][()], first.a)
    assert frames.shape == (5, 11, 3) and first.t == pytest.approx(0.1)
    assert np.all(frames[:, fixed] == 0.0)
    # The first frame holds the start's physical acceleration: gravity less mu v.
    start = read_frame(tmp_path / "first.h5", 0)
    free = ~fixed
    expected = -9.81 - 0.5 * start.v[free, 2]
    np.testing.assert_allclose(frames[0][free, 2], expected, rtol=1e-6)
    np.testing.assert_array_equal(
        read_frame(recover(tmp_path / "first.h5", tmp_path / "c.h5")).a, first.a
    )

    # An older file: no acceleration state, the restart starts from the physical one.
    with h5py.File(tmp_path / "c.h5", "r+") as h5:
        del h5["trajectory/a"], h5["result/a"]
    assert read_frame(tmp_path / "c.h5").a is None
    r = CliRunner().invoke(
        main,
        ["run", str(case), "-v", "-o", str(tmp_path / "o.h5"), "--restart", str(tmp_path / "c.h5")],
    )
    assert r.exit_code == 0 and "holds no newmark acceleration state" in r.output
    old = read_frame(tmp_path / "o.h5")
    off = np.abs(old.x - whole["x"]).max()
    assert 1e-9 * moved < off < 1e-2 * moved

    # implicit Euler keeps no acceleration state
    euler = run("-o", tmp_path / "euler.h5", "--set", "solver.integrator=implicit_euler")
    assert "a" not in euler
    with h5py.File(tmp_path / "euler.h5", "r") as h5:
        assert "a" not in h5["trajectory"] and "v" in h5["trajectory"]


@pytest.mark.parametrize("how", ["stop", "interrupt"])
def test_an_interrupted_newmark_run_restarts_exactly(tmp_path, how):
    """A run stopped between steps (stop) or within one (interrupt, as Ctrl-C) keeps the
    acceleration state of its last good step with the last frame and /result; the
    restart repeats the uninterrupted run to round-off."""
    case = parse_case(cable_case(0.2, rho_inf=0.8))
    whole = run_case(case, tmp_path / "whole.h5")
    calls = {"n": 0}

    def ask():
        calls["n"] += 1
        return calls["n"] >= (7 if how == "stop" else 15)

    kw = {"stop": ask} if how == "stop" else {"interrupt": ask}
    part = run_case(case, tmp_path / "part.h5", **kw)
    assert part.message == "interrupted" and 0 < part.steps < whole.steps
    assert part.a is not None and np.any(part.a != 0.0)
    with h5py.File(tmp_path / "part.h5", "r") as h5:
        np.testing.assert_array_equal(h5["trajectory/a"][-1], part.a)
        np.testing.assert_array_equal(h5["result/a"][()], part.a)
    rest = run_case(case, tmp_path / "rest.h5", restart=tmp_path / "part.h5")
    assert part.steps + rest.steps == whole.steps
    moved = np.abs(whole.x[:, 2]).max()
    assert np.abs(rest.x - whole.x).max() <= 1e-12 * moved


# --------------------------------------------------------------------------- the keys


def test_keys_reach_the_solver_and_bad_values_are_refused():
    case = parse_case(cable_case(0.1, rho_inf=0.7))
    settings = Settings.of(case.solver)
    assert (settings.integrator, settings.rho_inf) == ("newmark", 0.7)
    assert Settings().integrator == "implicit_euler"
    for bad, message in (
        ({"integrator": "rk4"}, "solver.integrator = 'rk4': must be one of"),
        ({"rho_inf": 1.5}, "solver.rho_inf = 1.5: must be in [0, 1]"),
        ({"rho_inf": -0.1}, "solver.rho_inf = -0.1: must be"),
    ):
        with pytest.raises(ConfigError, match=message.replace("[", r"\[").replace("]", r"\]")):
            parse_case(cable_case(0.1, **bad))
    with pytest.raises(ConfigError, match="solver.integrator"):
        Settings(integrator="midpoint")
    with pytest.raises(ConfigError, match="solver.rho_inf"):
        make("newmark", 2.0)


def test_rho_inf_without_newmark_is_reported_as_ignored():
    euler = parse_case(cable_case(0.1, integrator="implicit_euler", rho_inf=0.7)).solver
    assert any("solver.rho_inf = 0.7: ignored" in m for m in advice.ignored_solver_keys(euler))
    newmark = parse_case(cable_case(0.1, rho_inf=0.7)).solver
    assert advice.ignored_solver_keys(newmark) == []
    static = parse_case(cable_case(0.1, method="static")).solver
    assert any(
        "solver.integrator = 'newmark': ignored" in m for m in advice.ignored_solver_keys(static)
    )


def test_implicit_euler_is_the_default_and_unchanged():
    """Settings without an integrator run the paper's scheme: the same states as naming
    it, bit for bit."""
    net, loads, v0 = string()
    start = Start(v=v0)
    plain = solve(cn_problem(net, loads), Settings("dynamic", dt=1e-3, t_end=0.02), start=start)
    named = solve(
        cn_problem(net, loads),
        Settings("dynamic", dt=1e-3, t_end=0.02, integrator="implicit_euler"),
        start=start,
    )
    assert np.array_equal(plain.x, named.x) and np.array_equal(plain.v, named.v)


def cn_problem(net, loads):
    from catenet.scene import Scene

    return Scene(net, loads)


# --------------------------------------------------------------------------- mu's effect


def damping_config(mu: str, integrator: str) -> Path:
    """The damping study's case: the paper's (implicit Euler) or its newmark companion."""
    if integrator == "newmark":
        return CONFIGS / "dynamics" / f"damping_newmark_mu{mu}.toml"
    return CONFIGS / f"damping_mu{mu}.toml"


def short_damping_case(mu: str, integrator: str) -> dict:
    """The damping study's case, short: a coarser net (n = 4) with 4 times the density
    (the same equilibrium, the lowest period about that of the config) at dt = 0.02 s."""
    data = tomllib.loads(damping_config(mu, integrator).read_text())
    data["geometry"]["n"] = 4
    data["material"]["density"] = 4000.0
    data["solver"].update(dt=0.02, t_end=2000.0)
    data.pop("output", None)
    return data


def settling_time(mu: str, integrator: str) -> float:
    scene = build(parse_case(short_damping_case(mu, integrator)))
    assert scene.case.solver.integrator == integrator
    r = solve(scene, Settings.of(scene.case.solver))
    assert r.converged and r.equilibrium
    return r.time


def test_newmark_damping_configs_say_what_they_show():
    for mu in ("0.1", "1", "10"):
        path = damping_config(mu, "newmark")
        assert path.read_text().startswith("# Paper App. A, Fig. A.9, with the second-order")
        case = parse_case(tomllib.loads(path.read_text()))
        solver = case.solver
        assert (solver.integrator, solver.damping, solver.dt) == ("newmark", float(mu), 0.01)
        assert solver.t_end > 2 * 2 * np.log(1e8) / float(mu)  # room to come to rest


@pytest.mark.slow
def test_settling_time_follows_one_over_mu_with_newmark_only():
    """The damping study: with newmark the settling times of mu = 1 and 10 are about ten
    times apart (physics damps), with implicit Euler they are not (it damps
    numerically). (mu = 0.1 settles after about 250 s, 10^4 steps: see the benchmark
    study ``python -m benchmarks integrators``.)"""
    newmark = [settling_time(mu, "newmark") for mu in ("1", "10")]
    assert 7.0 < newmark[0] / newmark[1] < 13.0, newmark
    euler = [settling_time(mu, "implicit_euler") for mu in ("0.1", "1", "10")]
    assert euler[0] / euler[2] < 3.0, euler


# --------------------------------------------------------------------------- robustness


@pytest.mark.parametrize("dt", [0.3, 1.0])
def test_newmark_relaxes_the_paper_net_at_large_steps(dt):
    """The paper's n = 10 net (tension-only, p = 100 Pa, mu = 1) relaxed with newmark's
    default rho_inf at steps far beyond its lowest period (0.15 s) still comes to rest at
    the static equilibrium (with rho_inf = 0.9 it falls into a limit cycle at 0.1 s)."""
    sq = cn.square_net(10, 0.0, 1.0, 0.01, cn.Material.from_E(10e6, radius=0.01, density=1000.0))
    loads = cn.Loads(force=cn.pressure_force(sq.net, 100.0, 1.0))
    ref = cn.solve_static(sq.net, loads, rtol=1e-10)
    r = solve_dynamic(sq.net, loads, dt=dt, damping=1.0, t_end=200.0, integrator="newmark")
    assert r.equilibrium
    assert np.abs(r.x - ref.x).max() < 1e-6 * abs(ref.x[sq.center, 2])


@pytest.mark.parametrize("dt", [1e-1, 1e-2, 1e-3])
def test_newmark_keeps_every_node_outside_a_sphere(dt):
    """A net falling under its weight and a pressure onto a fixed sphere, with newmark:
    no node inside it at any accepted step of any step size."""
    from catenet.scene import Scene
    from catenet.terms.contact import SphereBarrier

    sq = cn.square_net(10, 0.3, 1.0, 0.05, cn.Material.from_E(10e6, radius=0.01, density=1000.0))
    net = sq.net
    loads = cn.Loads(force=cn.pressure_force(net, 300.0, 1.0), gravity=np.array([0, 0, -9.81]))
    ball = SphereBarrier(np.flatnonzero(~net.fixed), [0.0, 0.0, -0.23], 0.2, kappa=2e3, dhat=0.01)
    gaps = []
    r = solve(
        Scene(net, loads, (ball,)),
        Settings("dynamic", dt=dt, damping=5.0, t_end=0.3, integrator="newmark"),
        on_step=lambda s: gaps.append(float(ball.gap(s.x).min())),
    )
    assert r.converged and min(gaps) > 0.0
    assert ball.gap(r.x).min() < ball.dhat  # it did touch
