"""``catenet modes``: a case's equilibrium by the run's own path (``run_case``: the same
solve, result file and failures as ``catenet run``), then its lowest natural modes about
it (``catenet.solver.modes``), written into the result file (``catenet.output.modes``).

Bad input is found before anything is solved: a count that is not a positive integer or
exceeds the free DOFs, a net without mass (ConfigError, exit 2). A failed equilibrium
raises as ``catenet run``'s does (exit 1), as does a dynamic run that ends before rest.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from catenet.errors import ConfigError, ConvergenceError

if TYPE_CHECKING:  # the solvers load when a case is run
    from catenet.case.parse import Case
    from catenet.case.scene import Scene
    from catenet.solver.modes import Modes
    from catenet.solver.result import Result

__all__ = ["ModeRow", "ModesRun", "check_modes_input", "mode_rows", "modes_case"]

MOST = 3  # the summary names at most this many cables per mode
MOST_SHARE = 0.1  # ... each with at least this share of the mode's kinetic energy


def check_modes_input(scene, count) -> None:
    """ConfigError for a count that is not a positive integer or above the free DOFs,
    and for a net with no mass at its free nodes."""
    n_free = 3 * int(np.count_nonzero(~scene.net.fixed)) - 6 * len(scene.rigid)
    if scene.net.guides is not None:
        n_free -= scene.net.guides.held_count  # rollers and sliders
    torsion = scene.torsion
    if torsion is not None:
        if torsion.missing:
            raise ConfigError(torsion.missing)
        n_free += torsion.count  # the rods' twist angles
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1:
        raise ConfigError(f"--count = {count!r}: must be a positive integer")
    if count > n_free:
        raise ConfigError(
            f"--count = {count}: more than the net's {n_free} free DOFs (3 per free node, "
            "6 per free body, fewer on rollers and sliders, 1 per twisting edge): "
            f"ask for at most {n_free}"
        )
    if not float(np.sum(scene.net.mass[~scene.net.fixed])) > 0.0:
        from catenet.case.keys import show

        density = getattr(getattr(scene.case, "material", None), "density", 0)
        head = "the net's free nodes have no mass"  # (a density on fixed nodes only)
        if not density:
            head = f"material.density = {show(density)} and no [[mass]]"
        raise ConfigError(
            f"{head}: modes need mass, and the net has none where it moves (so no natural "
            "frequency): give material.density > 0 (per unstressed volume, "
            "with material.radius or material.area) or point masses ([[mass]] with node "
            "and mass)"
        )


def added_line(case: Case, scene: Scene) -> np.ndarray | None:
    """(E,) the added mass of water of each edge, Ca rho_w A l0 [kg] (its cable's
    [material] in a graph with cables, else [material]), sideways; with [water] (E, 2):
    rho_w A l0 times ca_n (sideways) and ca_t (along the edge); None where no material
    asks for any (``material.added_mass``, ``ca_n``, ``ca_t``)."""
    from catenet.case.keys import Checker
    from catenet.case.kinds.graph import GraphConfig
    from catenet.case.material import added_line_mass

    net = scene.net
    if case.water is not None:  # [water]: the materials' ca_n and ca_t
        from catenet.case.water import hydro_edges

        hydro = hydro_edges(case, scene)
        water = case.water.density * hydro.area * net.rest_length
        pair = np.column_stack([water * hydro.ca_n, water * hydro.ca_t])
        return pair if pair.any() else None
    base = added_line_mass(case.material)
    per_edge = np.full(net.n_edges, base)
    cables = scene.cables
    listed = case.geometry.cables if isinstance(case.geometry, GraphConfig) else ()
    if cables is not None and listed:
        from catenet.case.kinds.cables import cable_materials

        mats = cable_materials(Checker(), case.material, listed)
        line = [added_line_mass(m, f"geometry.cable[{c}].material") for c, m in enumerate(mats)]
        on = cables.edge >= 0
        per_edge[on] = np.asarray(line)[cables.edge[on]]
    if not per_edge.any():
        return None
    return per_edge * net.rest_length


@dataclass
class ModesRun:
    """What ``modes_case`` did: the equilibrium (a Result), the modes (None where the
    equilibrium did not converge: the Result says why), the file written (or None) and
    the scene."""

    result: Result
    modes: Modes | None
    path: Path | None
    scene: Scene
    load_case: str | None = None  # the load case or combination the modes are about


def modes_case(
    case,
    out=None,
    *,
    count: int = 10,
    progress=None,
    stop=None,
    interrupt=None,
    load_case: str | None = None,
) -> ModesRun:
    """Solves ``case`` as ``catenet run`` does (writing its result file, ``out`` or the
    case's output.file), then its ``count`` lowest modes, written into that file.
    ``load_case``: the modes about the state under that load case or combination
    (solved from the base state, as ``catenet run --case`` does); else about the base
    state (its load cases are solved too, as ``catenet run`` solves them)."""
    from catenet.case import build
    from catenet.output.modes import write_modes
    from catenet.run.runner import output_path, refuse_formfind, run_case
    from catenet.solver.modes import natural_modes

    refuse_formfind(case)
    scene = build(case)
    check_modes_input(scene, count)
    added = added_line(case, scene)
    kept = {}

    def done(scene, ws, result) -> None:
        kept["ws"] = ws

    result = run_case(
        case,
        out,
        progress=progress,
        stop=stop,
        interrupt=interrupt,
        scene=scene,
        on_done=done,
        load_case=load_case,
    )
    path = output_path(case, out)
    if load_case is not None and result.converged:  # (else the base state failed)
        (one,) = result.cases
        if one.result is None or not one.converged:
            message = one.error or (one.result.message if one.result else "not solved")
            failed = result if one.result is None else one.result
            failed.message = f"{one.name}: {message}"
            failed.converged = False
            return ModesRun(failed, None, path, scene, load_case)
        result = one.result
    if not result.converged:
        return ModesRun(result, None, path, scene, load_case)
    if not result.equilibrium:  # a dynamic run that reached t_end still moving
        raise ConvergenceError(
            f"modes: the dynamic run ended at t = {result.time:.6g} s before the net came to "
            "rest: no equilibrium to take the modes about; raise solver.t_end or use "
            "solver.method = 'static'"
        )
    if result.stable is False:
        raise ConvergenceError(f"modes: the equilibrium found is unstable: {result.diagnosis}")
    try:
        modes = natural_modes(
            kept["ws"], result.x, count, cables=scene.cables, added=added, torsion=scene.torsion
        )
    except ConfigError as exc:  # the input was sound: the equilibrium found holds nothing
        raise ConvergenceError(f"modes about the equilibrium found: {exc}") from None
    if path is not None:
        write_modes(path, scene, modes, about=load_case)
    return ModesRun(result, modes, path, scene, load_case)


@dataclass
class ModeRow:
    """One line of the summary's table."""

    k: int
    frequency: float
    period: float
    direction: str
    mass_share: np.ndarray  # (3,) effective mass / free mass per axis
    moves: str  # the cables (or the node) that move most
    twist_share: float = 0.0  # the share of its kinetic energy in the rods' twist


def mode_rows(scene, modes) -> list[ModeRow]:
    """The summary's table: per mode its frequency, period, dominant direction, the
    share of the free mass it carries along x, y, z, and what moves most: the cables
    with the largest shares of its kinetic energy (edge by edge, rho A l0 / 2 of each
    end), else the node that moves most."""
    net = scene.net
    cables = scene.cables
    dominant = modes.dominant()
    total = np.where(modes.total_mass > 0, modes.total_mass, 1.0)
    twist = modes.twist_share()
    rows = []
    for k in range(modes.count):
        torsional = twist[k] > 0.5
        if torsional:
            moves = _twists(net, modes, k, cables)
        else:
            moves = _body_moves(scene, modes.shape[k], modes.x) or _moves(
                net, modes.shape[k], cables
            )
        rows.append(
            ModeRow(
                k + 1,
                float(modes.frequency[k]),
                float(modes.period[k]),
                "tw" if torsional else dominant[k],
                modes.effective_mass[k] / total,
                moves,
                float(twist[k]),
            )
        )
    return rows


def _twists(net, modes, k: int, cables) -> str:
    """A torsional mode's "moves most": the cables with the largest shares of its twist's
    kinetic energy, else the edge that turns most, "(twist)" after them."""
    energy = modes.inertia * modes.twist[k] ** 2
    if cables is not None and len(cables.names):
        on = cables.edge >= 0
        per = np.bincount(cables.edge[on], energy[on], minlength=len(cables.names))
        if per.max() > 0:
            order = np.argsort(-per)[:MOST]
            names = [str(cables.names[c]) for c in order if per[c] >= MOST_SHARE * energy.sum()]
            if names:
                return ", ".join(names) + " (twist)"
    e = int(np.argmax(energy))
    return f"edge {e} ({net.edges[e, 0]}-{net.edges[e, 1]}) (twist)"


def _body_moves(scene, shape: np.ndarray, x: np.ndarray) -> str:
    """The free body that carries most of a mode's kinetic energy, if one carries at
    least half of it: "obstacle[k] (kind)", and "turning about [a, b, c]" where its
    rotation carries most of its own (else ""). The body's four nodes have masses m/4."""
    rigid = scene.rigid
    if not rigid:
        return ""
    mass = scene.net.mass
    total = float(np.einsum("n,nd,nd->", mass, shape, shape))
    best, share = None, 0.0
    for body in rigid:
        nodes = body.frame.nodes
        energy = float(np.einsum("n,nd,nd->", mass[nodes], shape[nodes], shape[nodes]))
        if total > 0 and energy / total > share:
            best, share = body, energy / total
    if best is None or share < 0.5:
        return ""
    nodes = best.frame.nodes
    label = f"obstacle[{best.obstacle}] ({scene.case.obstacles[best.obstacle].kind})"
    move = shape[nodes] - shape[nodes].mean(axis=0)  # w x r_k, r_k from the centre
    r = x[nodes] - x[nodes].mean(axis=0)
    if float(np.sum(move**2)) <= float(np.sum(shape[nodes].mean(axis=0) ** 2)) * 4:
        return label  # its translation carries most of its energy
    cross = np.zeros((4, 3, 3))  # -[r_k]x w = move_k
    cross[:, 0, 1], cross[:, 0, 2], cross[:, 1, 2] = r[:, 2], -r[:, 1], r[:, 0]
    cross -= cross.transpose(0, 2, 1)
    w = np.linalg.lstsq(cross.reshape(12, 3), move.ravel(), rcond=None)[0]
    w /= np.linalg.norm(w)
    axis = [round(float(v), 6) + 0.0 for v in w]  # + 0.0: no -0
    return f"{label} turning about [{', '.join(f'{v:.2g}' for v in axis)}]"


def _moves(net, shape: np.ndarray, cables) -> str:
    amplitude = np.einsum("nd,nd->n", shape, shape)
    if cables is not None and len(cables.names):
        half = 0.5 * net.line_density * net.rest_length
        energy = half * (amplitude[net.edges[:, 0]] + amplitude[net.edges[:, 1]])
        on = cables.edge >= 0
        per = np.bincount(cables.edge[on], energy[on], minlength=len(cables.names))
        total = float(energy.sum())
        if total > 0 and per.max() > 0:
            order = np.argsort(-per)[:MOST]
            names = [str(cables.names[c]) for c in order if per[c] >= MOST_SHARE * total]
            if names:
                return ", ".join(names)
    node = int(np.argmax(amplitude))
    return f"node {node}"
