"""docs/performance.md's scale tables (``python -m benchmarks render``), from scale.csv."""

from __future__ import annotations

from pathlib import Path

from benchmarks.sections import as_float, as_text, md_table, read_study


def scale(results: Path) -> list[str]:
    rows = read_study(results, "scale")
    if not rows:
        return []
    for r in rows:  # the guard's estimate by today's formula (it may have been recalibrated)
        if r.get("dofs") and r.get("n") and r.get("edge"):
            from benchmarks.scale import guard_estimate_mib

            r["guard_estimate_mib"] = guard_estimate_mib(int(r["n"]), as_float(r["edge"]))
            r["guard_ratio"] = r["guard_estimate_mib"] / as_float(r["peak_rss_mib"])
    main = [r for r in rows if r.get("variant", "default") == "default"]
    ok = [r for r in main if r.get("dofs")]
    if not ok:
        return []
    top = ok[-1]
    out = [f"Sizes from 1e3 to {as_float(top['dofs']):.0e} DOF:".replace("e+0", "e"), ""]
    out += md_table(
        [
            "DOF",
            "Newton it.",
            "total [s]",
            "set-up",
            "assembly",
            "analysis",
            "factorisation",
            "solves",
            "rest",
            "factor nnz",
            "peak RSS [MiB]",
            "guard's estimate [MiB]",
            "build net [s]",
        ],
        [
            [
                r["dofs"],
                r["iterations"],
                as_text(r["total_seconds"]),
                as_text(r["setup_seconds"]),
                as_text(r["assembly_seconds"]),
                as_text(r["analyse_seconds"]),
                as_text(r["factorize_seconds"]),
                as_text(r["solve_seconds"]),
                as_text(r["other_seconds"]),
                as_text(r["factor_nnz"], "{:.3g}"),
                as_text(r["peak_rss_mib"], "{:.0f}"),
                as_text(r.get("guard_estimate_mib"), "{:.0f}"),
                as_text(r["build_seconds"]),
            ]
            for r in ok
        ],
    )
    fit = [r for r in ok if as_float(r["dofs"]) >= 5e3]
    if len(fit) >= 3:
        from benchmarks.common import geometric_fit

        dofs = [as_float(r["dofs"]) for r in fit]
        b = geometric_fit(dofs, [as_float(r["total_seconds"]) for r in fit])[0]
        bf = geometric_fit(dofs, [as_float(r["factorize_seconds"]) for r in fit])[0]
        line = (
            f"Fitted cost exponents (log-log slope, DOF >= 5e3): total time ~ DOF^{b:.2f}, "
            f"numeric factorisation ~ DOF^{bf:.2f}"
        )
        cpu = [as_float(r.get("total_cpu_seconds")) for r in fit]
        if all(c > 0 for c in cpu):  # (nan > 0 is False: older tables lack the column)
            bc = geometric_fit(dofs, cpu)[0]
            line += f", the solve's CPU time (which a busy machine does not inflate) ~ DOF^{bc:.2f}"
        above = as_float(top["peak_rss_mib"]) - as_float(top["rss_after_import_mib"])
        if above > 0:
            line += (
                f"; memory: {as_text(above * 1024 / as_float(top['dofs']), '{:.2g}')} KiB "
                f"per DOF above the {as_text(top['rss_after_import_mib'], '{:.0f}')} MiB "
                "of a process that has loaded NumPy, Numba and MKL"
            )
        out += ["", line + "."]
    big = [r for r in fit if as_float(r["dofs"]) >= 1e5]
    if big:
        share = max(as_float(r["setup_seconds"]) / as_float(r["factorize_seconds"]) for r in big)
        ratios = [as_float(r.get("guard_ratio")) for r in ok]
        ratios = [q for q in ratios if q == q]
        text = (
            f"The largest size, {top['dofs']} DOF, takes {as_text(top['total_seconds'])} s "
            f"with a peak of {as_text(as_float(top['peak_rss_mib']) / 1024, '{:.2f}')} GiB. "
            "The set-up (the sparsity pattern, built at node level, and the solver's "
            f"handle) takes at most {share:.0%} of the numeric factorisation from 1e5 DOF on"
        )
        if ratios:
            text += (
                f"; the memory guard's estimate is {min(ratios):.2f} to {max(ratios):.2f} "
                "times the measured peak"
            )
        out += ["", text + "."]
    variants = [r for r in rows if r.get("variant", "default") != "default"]
    if variants:
        out += ["", "PARDISO's other choices at the same size:", ""]
        base = {r["dofs"]: r for r in ok}
        table = []
        for r in variants:
            ref = base.get(r.get("dofs"))
            if not r.get("dofs") or ref is None:
                table.append([r["n"], r["variant"], r.get("error", "")] + [""] * 6)
                continue
            table.append(
                [
                    r["dofs"],
                    r["variant"],
                    as_text(r["factor_nnz"], "{:.4g}"),
                    as_text(r["analyse_seconds"]),
                    as_text(r["factorize_seconds"]),
                    as_text(r["total_seconds"]),
                    as_text(
                        as_float(r["total_seconds"]) / as_float(ref["total_seconds"]), "{:.2f}"
                    ),
                    as_text(as_float(r["peak_rss_mib"]) / as_float(ref["peak_rss_mib"]), "{:.2f}"),
                ]
            )
        out += md_table(
            [
                "DOF",
                "variant",
                "factor nnz",
                "analysis [s]",
                "factorisation [s]",
                "total [s]",
                "time / default",
                "peak / default",
            ],
            table,
        )
    for r in rows:
        if r.get("error"):
            out += [
                "",
                f"n = {r['n']}, edge {r['edge']}, {r.get('variant', 'default')}: {r['error']}",
            ]
    return out
