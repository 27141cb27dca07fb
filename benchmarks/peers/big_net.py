"""The thrown net refined: the tether net of ``thrown_net.toml`` (20 m square, Dyneema
cords, 0.05 kg knots at its 2 m joints, 10 kg corner masses, thrown at 2 m/s, the corners
diverging) as a ``side`` x ``side`` grid of cords (``side = 101``: a 0.2 m mesh, 10 201
nodes, 30 615 DOF with the box), started ``gap`` above the free 8 t tumbling box so that
it meets the box within a few hundredths of a second: a short window around first
contact, frictionless (the floor has no friction).

``python benchmarks/peers/big_net.py [--side 101] [--gap 0.05] [--t-end 0.2] [--out DIR]``
writes ``DIR/thrown_net_<side>.json`` (the graph: nodes, edges, the sets "knots",
"corners" and "cords", the other nodes) and ``DIR/thrown_net_<side>.toml`` (the case),
a case as a user writes it (docs/reference/case-keys.md: geometry kind "graph" from a
JSON file).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

HERE = Path(__file__).resolve().parent
SIZE = 20.0  # m: the net's side
JOINTS = 11  # the coarse net's joints per side (2 m apart): the knots' 0.05 kg
BOX_TOP = 2.0  # m: the box's top face (half_size z)
CORNER_SPEED = 0.3  # m/s: the corners' outward speed, each direction
SIGNS = ((-1, -1), (1, -1), (-1, 1), (1, 1))  # the corners' outward directions

CASE = """\
# The thrown net of thrown_net.toml refined to a {side} x {side} grid of cords ({mesh:.3g} m
# mesh, {nodes} nodes), started {gap:g} m above the free 8 t box: first contact at about
# t = {touch:.3g} s. Written by benchmarks/peers/big_net.py.
title = "a thrown {side} x {side} net meeting a free tumbling box"

[geometry]
kind = "graph"
file = "{json}"

[material]
E = 100e9
radius = 0.002
density = 970.0

[[mass]]
node = "cords"
velocity = [0.0, 0.0, -2.0]

[[mass]]
node = "knots"
mass = 0.05
velocity = [0.0, 0.0, -2.0]
{corners}
[[obstacle]]
kind = "box"
center = [0.0, 0.0, 0.0]
half_size = [5.0, 2.0, 2.0]
mass = 8000.0
angular_velocity = [0.0, 0.035, 0.05]
distance = 0.02

[solver]
method = "dynamic"
t_end = {t_end:g}
damping = 0.0
"""

CORNER = """
[[mass]]
node = {node}
mass = 10.0
velocity = [{vx:g}, {vy:g}, -2.0]
"""


def graph(side: int, height: float) -> dict:
    """The grid's nodes (row by row, y then x), its edges (along x, then along y), the
    knots (the coarse net's joints but the corners) and the corners."""
    if side < 2 or (side - 1) % (JOINTS - 1):
        raise ValueError(f"side must be 10 k + 1 (the joints on the grid), not {side}")
    step = SIZE / (side - 1)
    nodes = [
        [round(-SIZE / 2 + i * step, 12), round(-SIZE / 2 + j * step, 12), height]
        for j in range(side)
        for i in range(side)
    ]
    edges = [[j * side + i, j * side + i + 1] for j in range(side) for i in range(side - 1)]
    edges += [[j * side + i, (j + 1) * side + i] for j in range(side - 1) for i in range(side)]
    every = (side - 1) // (JOINTS - 1)
    corners = [0, side - 1, side * (side - 1), side * side - 1]
    knots = [
        j * side + i
        for j in range(0, side, every)
        for i in range(0, side, every)
        if j * side + i not in corners
    ]
    return {
        "nodes": nodes,
        "edges": edges,
        "sets": {
            "cords": sorted(set(range(side * side)) - set(knots) - set(corners)),
            "knots": knots,
            "corners": corners,
        },
    }


def write(side: int = 101, gap: float = 0.05, t_end: float = 0.2, out: Path = HERE) -> Path:
    """Writes the graph and the case into ``out``; returns the case's path."""
    out.mkdir(parents=True, exist_ok=True)
    data = graph(side, BOX_TOP + gap)
    json_path = out / f"thrown_net_{side}.json"
    json_path.write_text(json.dumps(data, separators=(",", ":")))
    corners = "".join(
        CORNER.format(node=node, vx=sx * CORNER_SPEED, vy=sy * CORNER_SPEED)
        for node, (sx, sy) in zip(data["sets"]["corners"], SIGNS, strict=True)
    )
    case = out / f"thrown_net_{side}.toml"
    case.write_text(
        CASE.format(
            side=side,
            mesh=SIZE / (side - 1),
            nodes=side * side,
            gap=gap,
            touch=max(gap - 0.02, 0.0) / 2.0,
            json=json_path.name,
            corners=corners,
            t_end=t_end,
        )  # fmt: skip
    )
    return case


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--side", type=int, default=101)
    ap.add_argument("--gap", type=float, default=0.05, help="m above the box's top face")
    ap.add_argument("--t-end", type=float, default=0.2)
    ap.add_argument("--out", type=Path, default=HERE.parents[1] / "out" / "big_net")
    args = ap.parse_args(argv)
    print(write(args.side, args.gap, args.t_end, args.out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
