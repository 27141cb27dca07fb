"""Form finding of a case: the shape its [formfind] table asks for, the graph case that
``catenet run`` reproduces it with, and the result file (contract §5) beside it.

The case written (``to_case``) is a graph: the form-found positions, the edges, EA per
edge and the rest lengths l0 = L / (1 + eps) at which each edge carries its force N = q L
under the case's law, its fixed nodes, and the case's material, solver and output
settings. The loads the shape was found under go with it (point loads and pressure as
nodal forces per node, gravity as such), so that ``catenet run`` on it without further
load starts in equilibrium and reproduces the shape and forces.
"""

from __future__ import annotations

import dataclasses
import fnmatch
import json
import logging
import re
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from catenet.case.keys import show
from catenet.errors import ConfigError, ConvergenceError
from catenet.formfind import advice
from catenet.formfind.fdm import FormFound, formfind
from catenet.formfind.tocase import PREFIX, to_case

if TYPE_CHECKING:
    from catenet.case import Case

log = logging.getLogger(__name__)


#: Form finding again with area and line loads lumped on the shape found, until they
#: change by at most FOLLOW_TOL of the largest (FOLLOW_ITER times at most)
FOLLOW_TOL, FOLLOW_ITER = 1e-9, 50


def formfind_scene(scene) -> FormFound:
    """The shape of a case's scene as its [formfind] table says. By the force density
    method, area loads and line loads act on the shape found: the loads of the given
    geometry are lumped again on each shape found and the shape found again under them
    (the given geometry is only the start), until they agree to FOLLOW_TOL (a warning
    where they do not within FOLLOW_ITER)."""
    from catenet.case.scene import loads_at

    found = _formfind_once(scene)
    if scene.case.formfind is None or scene.case.formfind.method == "elastic":
        return found
    change = 0.0
    for _ in range(FOLLOW_ITER):
        follow = loads_at(scene, found.x, found.rest_length(PREFIX + "force_density"))
        if follow is None:
            return found
        used = scene.loads.force if scene.loads.force is not None else 0.0 * follow
        change = float(np.max(np.abs(follow - used), initial=0.0))
        if change <= FOLLOW_TOL * float(np.max(np.abs(follow), initial=0.0)):
            return found
        scene = dataclasses.replace(scene, loads=dataclasses.replace(scene.loads, force=follow))
        found = _formfind_once(scene)
    log.warning(
        "form finding: the area and line loads lumped on the shape found still changed by "
        "%.3g N at a node after %d shapes: the shape carries the last of them",
        change,
        FOLLOW_ITER,
    )
    return found


def _formfind_once(scene) -> FormFound:
    """The shape of a case's scene as its [formfind] table says, under its loads as
    built."""
    cfg = scene.case.formfind
    if cfg is None:
        raise ConfigError(
            "formfind: missing: the case needs a [formfind] table (force_density = q [N/m])"
        )
    net = scene.net
    if net.guides is not None or net.springs is not None:
        raise ConfigError(
            "formfind: the case has rollers, sliders or springs ([[supports.roller]], "
            "[[supports.slider]], [[supports.spring]]): the force density method holds "
            "fixed nodes only: form-find with those nodes fixed, then run the shape found "
            "with its rollers, sliders and springs"
        )
    if net.bodies:  # free bodies' nodes (no edges) stay where they are: the run moves them
        held = net.fixed | (np.arange(net.n_nodes) >= net.n_net)
        scene = dataclasses.replace(scene, net=net.replace(fixed=held))
    if cfg.method == "elastic":
        from catenet.formfind.elastic import formfind_elastic

        vary = cfg.vary or "cables"
        bounds = (cfg.rest_length_factor_min, cfg.rest_length_factor_max)
        if vary == "prestress":
            bounds = (cfg.prestress_min, cfg.prestress_max)
        return formfind_elastic(
            scene,
            targets=scene.case.targets,
            vary=vary,
            bounds=bounds,
            tol=cfg.tol,
            max_iter=cfg.max_iter,
            prefix=PREFIX,
            moves=cfg.supports,
        )
    if scene.case.targets:
        from catenet.formfind.design import formfind_targets

        return formfind_targets(
            scene,
            by_cable(scene, cfg.force_density, "force_density"),
            targets=scene.case.targets,
            vary=cfg.vary or "edges",
            bounds=(cfg.force_density_min, cfg.force_density_max),
            tol=cfg.tol,
            max_iter=cfg.max_iter,
            linear=scene.case.solver.linear,
            prefix=PREFIX,
            moves=cfg.supports,
        )
    return formfind(
        scene,
        by_cable(scene, cfg.force_density, "force_density"),
        method=cfg.method,
        force=by_cable(scene, cfg.force, "force"),
        length=by_cable(scene, cfg.length, "length"),
        tol=cfg.tol,
        max_iter=cfg.max_iter,
        linear=scene.case.solver.linear,
        prefix=PREFIX,
    )


OWN_EDGES = "edges"  # the key of a table by cable for the graph's own edges


def by_cable(scene, value, key: str):
    """A per-edge value of [formfind] as the form finding takes it: a table by cable
    (``{ name or pattern = value, edges = value }``) as one value per edge of the built
    net; a number or an array as given. ConfigError naming ``formfind.<key>`` when a
    key matches nothing, a cable twice, or an edge is left without a value."""
    if not isinstance(value, dict):
        return value
    path = f"{PREFIX}{key}"
    shown = _inline(value)
    cables = scene.cables
    if cables is None or not cables.names:
        raise ConfigError(
            f"{path} = {shown}: a table by cable needs a graph with [[geometry.cable]]: "
            "give one number, or one per edge"
        )
    names = list(cables.names)
    edge_cable = np.asarray(cables.edge)
    out = np.full(len(edge_cable), np.nan)
    given: dict[int, str] = {}  # cable index (-1: own edges) -> the key that gave it
    for pattern, v in value.items():
        hits = [c for c, n in enumerate(names) if fnmatch.fnmatchcase(n, pattern)]
        if pattern == OWN_EDGES and np.any(edge_cable < 0):
            hits.append(-1)
        if not hits:
            own = ", edges (the graph's own edges)" if np.any(edge_cable < 0) else ""
            raise ConfigError(
                f"{path}.{pattern} = {show(v)}: matches no cable (the cables: "
                f"{', '.join(names)}{own})"
            )
        for c in hits:
            if c in given:
                what = "the graph's own edges" if c < 0 else f"cable {names[c]!r}"
                raise ConfigError(
                    f"{path}.{pattern} = {show(v)}: {what} has a value already (from "
                    f"{path}.{given[c]}): give each cable one"
                )
            given[c] = pattern
            out[edge_cable == c] = v
    left = np.flatnonzero(np.isnan(out))
    if left.size:
        c = int(edge_cable[left[0]])
        what = "the graph's own edges (key edges)" if c < 0 else f"cable {names[c]!r}"
        raise ConfigError(f"{path} = {shown}: gives no value for {what}: give every edge one")
    return out


def _inline(table: dict) -> str:
    """A table as TOML writes it inline: ``{ "hang*" = 45000.0, edges = 1000.0 }``."""
    bare = re.compile(r"^[A-Za-z0-9_-]+$")
    items = (f"{k if bare.match(k) else json.dumps(k)} = {show(v)}" for k, v in table.items())
    return "{ " + ", ".join(items) + " }"


@dataclass
class Written:
    """What ``write_formfind`` made: the shape, the case it wrote (parsed) and the files."""

    found: FormFound
    case: object
    result_file: Path
    case_file: Path
    scene: object = None  # the form-finding case's scene (its cables and node sets)


def case_file_for(out: Path) -> Path:
    """The case file written beside the result file ``out``: OUT.toml."""
    return out.with_suffix(".toml")


def write_formfind(case: Case, out: str | Path | None = None) -> Written:
    """Form-finds ``case`` and writes the result file ``out`` (default: the case's
    output.file) and the case OUT.toml beside it. Nothing is written when the input is
    bad or the targets cannot be met."""
    from catenet.case import build, parse_case
    from catenet.output import ResultWriter, check_output_path

    start = time.perf_counter()
    out = Path(case.output.file if out is None else out)
    toml_path = case_file_for(out)
    if toml_path == out:  # the case file would replace the result file
        raise ConfigError(
            f"output file {str(out)!r}: is the name of the case file written beside the "
            "result file (OUT.toml beside OUT.h5): give the result file, such as out/net.h5"
        )
    check_output_path(out)
    check_output_path(toml_path, what="case file")
    source = Path(case.source or "")
    for p in (out, toml_path):
        if source.is_file() and p.exists() and p.resolve() == source.resolve():
            raise ConfigError(f"output file {str(p)!r}: is the case file itself: give another -o")
    scene = build(case)
    for slip in advice.slips(case, scene):  # a material no cable is made of
        log.warning("%s", slip)
    try:
        found = formfind_scene(scene)
    except (ConfigError, ConvergenceError) as exc:  # (in the case's units)
        raise advice.explained(exc, case, scene) from None
    for message in advice.warnings(found, case):
        log.warning("%s", message)
    run_file = str(out.with_name(out.stem + "_run" + out.suffix))
    data = to_case(found, case, output_file=run_file, scene=scene)
    written = parse_case(data, source=str(toml_path), base_dir=toml_path.parent)
    resolved = written.to_toml()  # the case file's text and the result file's, once
    result_scene = build(written)
    res = _result(found, result_scene, time.perf_counter() - start)
    attrs = {
        "case": resolved,
        "title": written.title,
        "linear_backend": found.backend,
        "source": str(case.source),
        "formfind_method": found.method,
        "formfind_case": str(toml_path),
    }
    if not written.title:
        del attrs["title"]
    plain = dataclasses.replace(result_scene, case=None)  # (its text is attrs["case"])
    with ResultWriter(
        out, plain, every=case.output.every, xdmf=case.output.xdmf, attrs=attrs
    ) as writer:
        if writer.wants(0):
            writer.frame(1.0, res.x, None, res.tension, last=True)
        writer.result(
            res,
            formfind_residual=float(found.residual),
            factorizations=int(found.factorizations),
        )
    if found.design is not None:
        from catenet.formfind import report

        report.write(out, found)
    toml_path.parent.mkdir(parents=True, exist_ok=True)
    toml_path.write_text(_header(case, found, out) + resolved, encoding="utf-8")
    return Written(found, written, out, toml_path, scene)


def _header(case: Case, found: FormFound, out: Path) -> str:
    src = case.source or "<dict>"
    targets = ""
    if found.design is not None:
        from catenet.formfind import report
        from catenet.model.units import relabel

        lines = relabel(report.header_lines(found), case.units or "SI")
        targets = "".join(f"# {line}\n" for line in lines)
    claim = (
        "# The last iterate of a target search that found no answer (below: `catenet "
        "formfind` says why): no design, kept to show where the search went."
        if no_answer(found)
        else "# `catenet run` on this case, without further load, reproduces the shape "
        "and the forces."
    )
    return (
        f"# Form found by `catenet formfind {src}` (method = {found.method!r}; result file "
        f"{out}).\n{claim}\n{targets}\n"
    )


def no_answer(found: FormFound) -> bool:
    """Whether a target search ended in no answer: out of iterations or run away with
    targets unmet, or at a state no cable reaches (strains beyond its law's range)."""
    from catenet.formfind.design import RAN_AWAY

    d = found.design
    if d is None:
        return False
    ran = not d.all_met and d.message in (RAN_AWAY, "formfind.max_iter reached")
    return ran or bool(d.extra.get("implausible"))


def _result(found: FormFound, scene, wall_time: float):
    """The form-found state as a Result of the written scene (tensions from its law)."""
    from catenet.model import measures
    from catenet.solver.result import Result

    net = scene.net
    tension = measures.tension(net, found.x)
    e = found.x[net.edges[:, 1]] - found.x[net.edges[:, 0]]
    w = (tension / np.linalg.norm(e, axis=1))[:, None] * e
    grad = np.zeros_like(found.x)
    np.subtract.at(grad, net.edges[:, 0], w)
    np.add.at(grad, net.edges[:, 1], w)
    load = scene.loads.external_force(net)
    free = ~net.fixed
    residual = float(np.max(np.abs(grad[free] - load[free]), initial=0.0))
    return Result(
        x=found.x.copy(),
        tension=tension,
        reaction=measures.reaction(net, grad, load),
        converged=True,
        iterations=int(found.iterations),
        residual=residual,
        steps=1,
        time=1.0,
        equilibrium=True,
        wall_time=wall_time,
        message=f"form found ({found.method})",
        max_strain=measures.max_strain(net, found.x),
    )
