"""What form finding says beside its shape, as `catenet run` says it of a state: the
material numbers no cable is made of (a unit slip: before the search, and in a failure's
message as its likely cause), strains beyond the law's range, and a shape that hangs
far beyond its supports' span (an equilibrium, but force densities far too low for the
loads), all in the case's units."""

from __future__ import annotations

import numpy as np

from catenet.errors import CatenetError, ConfigError
from catenet.model.units import relabel

#: A shape this many times its supports' span across is warned of (``catenet run``'s
#: node moved beyond 10 times the structure's size)
FAR = 10.0


def slips(case, scene) -> list[str]:
    """The unit slips of the case's material and area loads (``catenet.run.advice``)."""
    from catenet.run.advice import unit_slips

    return unit_slips(case, scene.net)


def explained(exc: CatenetError, case, scene) -> CatenetError:
    """``exc`` with its message in the case's units and the likely unit slip after it."""
    units = case.units or "SI"
    found = slips(case, scene)
    if isinstance(exc, ConfigError):  # (its problems are what is printed)
        exc.problems = relabel(exc.problems, units)
        if found:
            exc.problems[-1] = f"{exc.problems[-1]}; {found[0]}"
        exc.args = ("\n".join(exc.problems),)
        return exc
    message = relabel([str(exc)], units)[0]
    if found:
        message = f"{message}; {found[0]}"
    exc.args = (message, *exc.args[1:])
    return exc


def warnings(found, case) -> list[str]:
    """A found shape's strains beyond its law's range and an extent beyond FAR times its
    supports' span, in the case's units ([] for neither, and for a target search that
    ended in no answer: its error says why)."""
    from catenet.formfind.design import RAN_AWAY
    from catenet.run.advice import strain_beyond_law

    d = found.design
    if d is not None and (
        d.extra.get("implausible") or d.message in (RAN_AWAY, "formfind.max_iter reached")
    ):
        return []

    net = found.net.replace(rest_length=found.rest_length())
    out = []
    beyond = strain_beyond_law(net, found.x)
    if beyond:
        out.append(beyond)
    fixed = found.net.nodes[found.net.fixed]
    span = float(np.linalg.norm(np.ptp(fixed, axis=0))) if len(fixed) > 1 else 0.0
    extent = float(np.linalg.norm(np.ptp(found.x, axis=0)))
    if span > 0.0 and extent > FAR * span:
        out.append(
            f"the shape found is {extent:.4g} m across, {extent / span:.3g} times its "
            f"supports' span ({span:.4g} m): an equilibrium, but one of force densities "
            "far too low for the loads (raise them for a shallower shape)"
        )
    return relabel(out, case.units or "SI")
