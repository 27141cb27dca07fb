"""``catenet formfind``: find the shape of a case's net by the force density method."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from catenet.cli.common import (
    EXIT_FAILED,
    EXIT_OK,
    HELP,
    PathParam,
    case_options,
    errors_to_exit_codes,
    setup_logging,
    verbosity_options,
)


@click.command(name="formfind", context_settings=HELP)
@click.argument(
    "case_file",
    metavar="CASE.toml",
    type=PathParam(exists=True, dir_okay=False, give="a case file"),
)
@case_options(
    "Result file (default: the case's output.file); the case OUT.toml goes beside it.",
    "formfind.force_density=2",
)
@verbosity_options
def command(
    case_file: Path,
    out: Path | None,
    overrides: tuple[str, ...],
    quiet: bool,
    verbose: int,
    debug: bool,
) -> None:
    """Find the shape of CASE.toml's net that carries the forces its [formfind] table
    asks for (force densities, target forces or target lengths), or the force densities,
    rest lengths or supports' positions ([[formfind.support]]) that reach its [[target]]
    tables (nodes' positions, nodes on a surface, cables' tensions and lengths, supports'
    reactions: each target's achieved value is reported), and write the result file
    OUT.h5 and the graph case OUT.toml beside it: form-found positions and the rest
    lengths that carry those forces, which `catenet run OUT.toml` reproduces.

    \b
    Exit status: 0 found ([[target]]s not all met: the weighted least-squares
    compromise, with a warning); 1 failed while running, or the target search did not
    converge within formfind.max_iter or its force densities ran away (its last iterate
    written), or the shape found strains an edge beyond 10 times its law's range (under
    self-weight: force densities too low for the weight); 2 bad input (case file, --set
    values, paths, force densities that make nodes coincide, target forces or lengths of
    method "forces" or "lengths" that cannot be met, hard targets unmet).
    """
    setup_logging(quiet, verbose, debug)
    with errors_to_exit_codes(debug):
        from catenet.case import load_case
        from catenet.formfind import write_formfind
        from catenet.solver.threads import set_threads

        case = load_case(case_file, overrides)
        set_threads(case.solver.threads)
        written = write_formfind(case, out)
        if not quiet:
            _summary(written)
        if unconverged := _unconverged(written):
            from catenet.model.units import relabel

            source = getattr(written.scene, "case", None) or written.case
            units = getattr(source, "units", None) or "SI"
            unconverged = relabel([unconverged], units)[0]  # its forces in the case's units
            click.echo(f"catenet: error: {unconverged}", err=True)
            sys.exit(EXIT_FAILED)
    sys.exit(EXIT_OK)


def _unconverged(written) -> str:
    """Why a target search's end is no answer: it ran out of iterations, or its force
    densities ran away, or it stopped (met, or a least-squares compromise) at a state no
    cable reaches; "" for any other end."""
    from catenet.formfind.design import RAN_AWAY, RUNAWAY

    f = written.found
    d = f.design
    if d is None:
        return ""
    if d.all_met or d.message not in (RAN_AWAY, "formfind.max_iter reached"):
        return _implausible(d, f.method)
    bounds = (
        "formfind.rest_length_factor_min / _max, or prestress_min / _max"
        if f.method == "elastic"
        else "formfind.force_density_min / _max"
    )
    if d.extra.get("moved"):
        bounds += ", or the ranges of [[formfind.support]]"
    if d.message == RAN_AWAY:
        ran = float(d.extra.get("ran", RUNAWAY))
        way = f"to {ran:.3g} times" if ran > 1.0 else f"down to {ran:.3g} of"
        why = f"the force densities ran away ({way} their start, beyond {RUNAWAY:.0e})"
        more = ""
    else:  # formfind.max_iter reached
        why = (
            "the target search did not converge within formfind.max_iter = "
            f"{written.scene.case.formfind.max_iter} iterations"
        )
        more = (
            "a larger formfind.max_iter where the misses were still falling (targets that "
            "two variables move alike, a rest length and an anchor's position for a sag "
            "and a pull, converge slowly); "
        )
    return (
        f"{why} (its last iterate written, its targets NOT met: tensions up to "
        f"{float(f.force.max()):.3g} N): {more}a target that only ever larger or smaller "
        "forces approach (a node asked to lie where the loads cannot hold it) has no "
        f"optimum; check the targets, or bound the search ({bounds})"
    )


def _implausible(d, method: str) -> str:
    """Why a search that ended at a stationary point (its targets met or the
    compromise) reached no cable's state ("" where it did)."""
    if not d.extra.get("implausible"):
        return ""
    bound = (
        "the rest lengths (formfind.rest_length_factor_min / _max)"
        if method == "elastic"
        else "the force densities (formfind.force_density_min / _max)"
    )
    return (
        f"{d.extra['implausible']} (its last iterate written): check the targets, or bound {bound}"
    )


def _steps(d) -> str:
    """How a large search's damped steps went (conjugate residuals,
    ``catenet.formfind.krylov``, or the direct factorisation where they did not
    converge); '' for a small one."""
    steps = d.extra.get("steps")
    if not steps:
        return ""
    failed = steps["fallbacks"]
    why = f" ({failed} where they did not converge)" if failed else ""
    return (
        f"; damped steps: {steps['iterative']} by conjugate residuals "
        f"({steps['iterations']} iterations), {steps['factorizations']} direct{why}; "
        f"{steps['products']} products with the Jacobians (a solve each)"
    )


def _summary(written) -> None:
    import numpy as np

    f = written.found
    force = f.force
    detail = (
        "one factorisation"
        if f.method == "linear"
        else f"{f.iterations} iterations, {f.factorizations} factorisations, "
        f"targets met to {f.residual:.2g}"
    )
    if f.design is not None:
        d = f.design
        solves = "equilibria" if f.method == "elastic" else "factorisations"
        detail = (
            f"{d.message}: {d.evaluations} iterations, {d.gradients} adjoint gradients, "
            f"{f.factorizations} {solves}{_steps(d)}"
        )
    from catenet.model.units import relabel

    source = getattr(written.scene, "case", None)  # the case as given: its units
    case = written.case
    units = (source or case).units or "SI"
    lines = [
        f"{'method':<12} {f.method} ({detail})",
        f"{'net':<12} {f.net.n_net} nodes, {f.net.n_edges} edges, "
        f"{int(np.count_nonzero(f.net.fixed[: f.net.n_net]))} fixed",
        f"{'tension':<12} {float(force.min()):.6g} .. {float(force.max()):.6g} N",
        f"{'density':<12} {float(f.q.min()):.6g} .. {float(f.q.max()):.6g} N/m "
        "(force densities q = tension / length)",
        *shape_lines(f, written.scene),
        *_targets(f),
        f"{'wall time':<12} {f.wall_time:.3g} s ({f.backend})",
    ]
    lines = [  # labelled in the case's units (numbers as it wrote them), not the title
        f"{'case':<12} {case.title or case.source}",
        *relabel(lines, units),
        f"{'output':<12} {written.result_file}",
        f"{'case file':<12} {written.case_file} "
        + (
            "(the last iterate: no answer)"
            if _unconverged(written)
            else f"(catenet run {written.case_file})"
        ),
    ]
    click.echo("\n".join(lines))
    if f.design is not None and not f.design.all_met and not _unconverged(written):
        from catenet.formfind.design import BLOCKED

        shape = (
            "the nearest the search got with force densities that give a shape"
            if f.design.message.startswith(BLOCKED)
            else "the weighted least-squares compromise"
        )
        click.echo(
            f"catenet: warning: the targets are not all met: the shape is {shape} (misses above)",
            err=True,
        )


def _targets(f) -> list[str]:
    """The design variables found and each target's achieved value."""
    if f.design is None:
        return []
    from catenet.formfind import report

    d = f.design
    what = "edge" if d.vary == "edges" else "cable"
    moved = d.extra.get("moved", 0)  # the supports' offsets: the last of the variables
    offsets = list(d.extra.get("offsets_at_bound", ()))
    main = d.at_bound - sum(offsets)
    bound = f", {main} at a bound" if main else ""
    if f.method == "elastic" and d.extra.get("kind") == "prestress":
        t = d.extra["values"][: len(d.extra["values"]) - moved]
        design = (
            f"{d.variables - moved} prestresses (one per cable): {float(t.min()):.9g} .. "
            f"{float(t.max()):.9g} N{bound}"
        )
    elif d.vary == "supports":
        design = f"{d.variables} support offset{'s' if d.variables > 1 else ''}{bound}"
    elif f.method == "elastic":
        rest = f.net.rest_length
        design = (
            f"{d.variables - moved} rest-length factors (one per {what}): rest lengths "
            f"{float(rest.min()):.9g} .. {float(rest.max()):.9g} m, "
            f"{float(rest.sum()):.12g} m in all{bound}"
        )
    else:
        design = (
            f"{d.variables - moved} force densities (one per {what}): "
            f"{float(f.q.min()):.6g} .. {float(f.q.max()):.6g} N/m{bound}"
        )
    out = [f"{'design':<12} {design}"]
    if moved:
        names, values = d.extra["names"][-moved:], d.extra["values"][-moved:]
        for name, value, held in zip(names, values, offsets or [False] * moved, strict=True):
            at = " (at a bound of its range)" if held else ""
            out.append(f"{'moved':<12} {name}: {float(value):+.9g} m{at}")
    out += [f"{f'target[{r.k}]':<12} {r.line()}" for r in report.rows(d)]
    return out


def shape_lines(f, scene) -> list[str]:
    """What the shape found is: the supports' span, the lowest and highest node, each
    node set's height against the supports (a rise above them, a sag below), and per
    cable its tension and force-density range."""
    import numpy as np

    n = f.net.n_net
    x = f.x[:n]
    fixed = np.flatnonzero(f.net.fixed[:n])
    lines = []
    if fixed.size >= 2:
        plan = x[fixed, :2]
        span = float(np.max(np.linalg.norm(plan[:, None] - plan[None], axis=2)))
        lines.append(f"{'span':<12} {span:.6g} m (the largest plan distance between supports)")
    low, high = int(np.argmin(x[:, 2])), int(np.argmax(x[:, 2]))
    lines.append(
        f"{'height':<12} lowest node {low} at z = {x[low, 2]:.6g} m, highest node {high} at "
        f"z = {x[high, 2]:.6g} m"
    )
    base = float(x[fixed, 2].mean()) if fixed.size else 0.0
    sets = {} if scene is None else dict(scene.sets or {})
    for name, nodes in sets.items():
        if str(name).startswith("cable:") or not len(nodes):
            continue
        if f.net.fixed[np.asarray(nodes, dtype=np.int64)].all():
            continue  # (supports: form finding does not move them)
        z = x[np.asarray(nodes, dtype=np.int64), 2]
        rise = float(z.mean()) - base
        what = "rise" if rise >= 0 else "sag"
        lines.append(
            f"{'set':<12} {name}: z = {z.min():.6g} .. {z.max():.6g} m, {what} "
            f"{abs(rise):.6g} m (its mean against the supports' mean z = {base:.6g} m)"
        )
    cables = None if scene is None else scene.cables
    if cables is not None:
        force, q = f.force, f.q
        for k, name in enumerate(cables.names):
            on = np.asarray(cables.edge) == k
            if on.any():
                lines.append(
                    f"{'cable':<12} {name}: tension {force[on].min():.6g} .. "
                    f"{force[on].max():.6g} N, q {q[on].min():.6g} .. {q[on].max():.6g} N/m"
                )
    return lines


__all__ = ["command"]
