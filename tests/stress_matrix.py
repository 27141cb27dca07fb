"""The stress test's scene matrix: hard scenes, each checked against what is right.

Every scene must end in one of two ways: a converged answer that passes its check, or a
clear catenet error (``CatenetError``) where that is the right answer. Anything else (a
non-catenet exception, a NaN in a result, a check that fails) is a finding. Checks:

- ``eq17``: cable under a midpoint load against Eq. 17 (``catenet.validate.analytic``), exact for
  the discrete model; relative error of delta.
- ``chain``: cable under self-weight against the exact discrete chain
  (``catenet.validate.analytic.discrete_catenary``, the same model solved in closed form).
- ``equilibrium``: residual at the free nodes and the balance of reactions and applied
  loads, relative to the load scale, recomputed here from the returned state.
- ``static = dynamic``: the dynamic run's final equilibrium against the static one.
- ``bounded``: a dynamic run stopped long before equilibrium stays finite and bounded.

``scenes(quick)`` lists them (the quick subset runs in ``tests/solver/test_stress.py``, the
whole matrix in ``benchmarks/stress.py``); ``run_scene`` runs one and returns its row. The
scenes and their checks are in ``tests/scenes.py``.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from scenes import (
    bilateral_chain,
    bilateral_compression,
    finite,
    midpoint_load,
    net_point_load,
    net_pressure,
    paper_material,
    random_graph,
    self_weight,
)

log = logging.getLogger(__name__)

SLOW_SECONDS = 10.0  # a scene slower than this is reported
EQ_TOL = 1e-6  # relative residual / reaction balance of a converged state


@dataclass(frozen=True)
class Scene:
    """One hard scene. ``fn(**params)`` returns a dict with ``results`` (list of Result),
    ``check``, ``value``, ``tol`` and optionally ``note``. ``errors_ok``: catenet error
    classes (names) that are a right answer here."""

    id: str
    group: str
    fn: Callable[..., dict]
    params: dict = field(default_factory=dict)
    quick: bool = True
    errors_ok: tuple[str, ...] = ()


def scenes(quick: bool = False) -> list[Scene]:
    """The scene matrix; ``quick``: the subset the tests run (about a minute)."""
    out: list[Scene] = []

    def add(id_, group, fn, quick_=True, errors_ok=(), **params):
        out.append(Scene(id_, group, fn, params, quick_, tuple(errors_ok)))

    for fb in (1e-9, 1e-6, 1e-3, 1e-2, 0.1, 0.5):
        add(f"midpoint F/EA={fb:g}", "load range", midpoint_load, F_bar=fb)
    for ea in (1e-2, 1.0, 1e3, 1e6, 1e9):
        add(f"midpoint F=1N EA={ea:g}", "EA range", midpoint_load, F=1.0, EA=ea)
    for h in (1e-6, 1e-4, 1e-2, 1.0, 1e3):
        steps = 200 if h <= 1e-4 else None
        add(
            f"midpoint dynamic h={h:g}",
            "time step range",
            midpoint_load,
            F_bar=1e-2,
            method="dynamic",
            h=h,
            steps=steps,
            quick_=h >= 1e-4,
        )
    for mu in (0.0, 1e-2, 1.0, 1e2, 1e3):
        add(
            f"midpoint dynamic mu={mu:g}",
            "damping range",
            midpoint_load,
            F_bar=1e-2,
            method="dynamic",
            h=1e-2,
            damping=mu,
            quick_=mu in (0.0, 1e3),
        )
    add("zero-slack self-weight static", "self-weight", self_weight, dL=0.0)
    add("zero-slack self-weight EA=1e9", "self-weight", self_weight, dL=0.0, EA=1e9)
    add(
        "zero-slack self-weight dynamic",
        "self-weight",
        self_weight,
        dL=0.0,
        method="dynamic",
        h=1e-2,
        quick_=False,
    )
    add("supports inward L/2 static", "moved supports", self_weight, dL=0.5)
    add(
        "supports inward L/2 dynamic",
        "moved supports",
        self_weight,
        dL=0.5,
        method="dynamic",
        h=1e-2,
        ramp=1.0,
        quick_=False,
    )
    add("supports inward 0.9 L static", "moved supports", self_weight, dL=0.9)
    add(
        "supports inward 0.2 L dynamic h=0.1 ramp 0.5 s",
        "moved supports",
        self_weight,
        dL=0.2,
        method="dynamic",
        h=0.1,
        ramp=0.5,
    )
    add(
        "supports inward L/2 dynamic h=1e3 ramp 1 s",
        "moved supports",
        self_weight,
        dL=0.5,
        method="dynamic",
        h=1e3,
        ramp=1.0,
    )
    errs = ("ConvergenceError", "SingularSystemError")
    add("bilateral compressed, no load", "bilateral", bilateral_compression, errors_ok=errs)
    add(
        "bilateral compressed, perturbed start",
        "bilateral",
        bilateral_compression,
        perturb=1e-3,
        errors_ok=errs,
    )
    add(
        "bilateral compressed, dynamic",
        "bilateral",
        bilateral_compression,
        method="dynamic",
        perturb=1e-3,
        errors_ok=errs,
        quick_=False,
    )
    add("bilateral compressed, gravity", "bilateral", bilateral_compression, gravity=True)
    # Issue 13: EA / weight from 1e2 to 1e9, supports moved inward by 1 % to 90 %, one load
    # step; the quick subset keeps the corners and the issue's own scene (EA = 1e6 N,
    # rho A = 1 kg/m, 10 %).
    for ratio in (1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9):
        for dL in (0.01, 0.1, 0.3, 0.5, 0.9):
            corner = ratio in (1e2, 1e9) and dL in (0.01, 0.9)
            add(
                f"bilateral chain EA/W={ratio:g} inward {dL:g}",
                "bilateral sweep",
                bilateral_chain,
                ratio=ratio,
                dL=dL,
                quick_=corner,
            )
    add(
        "bilateral chain EA=1e6 N rho A=1 kg/m inward 0.1",
        "bilateral sweep",
        bilateral_chain,
        ratio=1e6 / 9.81,
        dL=0.1,
    )
    add("net point load", "net", net_point_load)
    add("net point load F=0.5 EA", "net", net_point_load, F=0.5 * paper_material().EA, quick_=False)
    for lb in (1e-9, 1e-3, 0.5):
        add(f"net p L^2/EA={lb:g}", "net", net_pressure, load_bar=lb, quick_=lb != 1e-3)
    add(
        "net p L^2/EA=1e-3 static=dynamic",
        "net",
        net_pressure,
        load_bar=1e-3,
        dynamic=True,
        quick_=False,
    )
    add("cable 1e5 edges", "size", midpoint_load, F_bar=1e-2, nodes=100_001)
    for seed in range(6):
        add(
            f"random graph seed={seed}",
            "random graphs",
            random_graph,
            seed=seed,
            errors_ok=("ConfigError",),
            quick_=seed < 3,
        )
    return [s for s in out if s.quick] if quick else out


def run_scene(scene: Scene) -> dict:
    """Runs one scene; never raises. ``passed``: a right answer (see the module doc)."""
    from catenet.errors import CatenetError

    row: dict[str, Any] = {
        "id": scene.id,
        "group": scene.group,
        "params": ", ".join(f"{k}={v}" for k, v in scene.params.items()),
    }
    start = time.perf_counter()
    try:
        out = scene.fn(**scene.params)
    except CatenetError as exc:
        name = type(exc).__name__
        row.update(
            status=f"error: {name}",
            passed=name in scene.errors_ok,
            message=str(exc).splitlines()[0][:300],
            iterations=getattr(exc, "iterations", None),
            history=_history(getattr(exc, "history", [])),
        )
    except Exception as exc:  # not a catenet error: always a finding
        log.warning("stress %s: %r", scene.id, exc)
        row.update(
            status=f"BUG: {type(exc).__name__}",
            passed=False,
            message=f"{type(exc).__name__}: {exc}"[:300],
        )
    else:
        results = out["results"]
        ok_finite = all(finite(r) for r in results)
        converged = all(r.converged for r in results)
        value, tol = out["value"], out["tol"]
        eq = out.get("equilibrium_error", 0.0)
        check_ok = math.isfinite(value) and value <= tol
        passed = ok_finite and check_ok and eq <= EQ_TOL
        status = "converged" if converged else "not converged"
        if not ok_finite:
            status = "NaN in result"
        row.update(
            status=status,
            passed=passed,
            check=out["check"],
            value=value,
            tol=tol,
            equilibrium_error=eq,
            iterations=sum(r.iterations for r in results),
            steps=sum(r.steps for r in results),
            message=out.get("note", ""),
            history=_history(results[0].history),
        )
    row["seconds"] = time.perf_counter() - start
    row["slow"] = row["seconds"] > SLOW_SECONDS
    return row


def _history(history) -> str:
    h = list(history)
    if len(h) > 8:
        h = h[:3] + ["..."] + h[-4:]
    return " ".join(x if isinstance(x, str) else f"{x:.2e}" for x in h)
