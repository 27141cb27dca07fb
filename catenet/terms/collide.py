"""Rigid balls against boxes, capsules and meshes, fixed or on a prescribed motion.

A moving sphere (``catenet.scene.bodies``) is one node, its centre c, of radius r. Its
contact with a shape is the shape's own barrier term (``catenet.terms.shapes``) acting
on that one node, with the gap measured to the Minkowski sum of the shape and the ball:

    g = d - r,   d the centre's distance to the shape,

a box rounded by r (``BoxBarrier(offset=r)``), a capsule of radius R + r (exact: a capsule is
already a segment grown by a radius) and a mesh grown by r (``MeshBarrier(offset=r)``). The
energy kappa b(g) has the gradient kappa b'(g) n and the Hessian
kappa (b''(g) n n^T + b'(g) (P - n n^T) / d): the barrier's derivatives at the gap, the
curvature of the offset surface over the true distance d (``catenet.kernels.shapes``).

Guarantee, the same as for every contact term: the ball never overlaps the shape, in
static and dynamic runs, at any step size. The barrier is infinite at g <= 0, a ball that
starts overlapping is refused (``catenet.scene.bodies``), and the line search and every
predictor are capped at ``max_step``, the exact first contact of the centre's straight
motion with the offset surface: for the box the entry of the ray into the rounded box
(its three slabs grown by r and the 12 capsules of radius r on its edges, whose end balls
are the corner balls), for the mesh the entry into the union of its triangles grown by r
(each one's prism of half-thickness r and the capsules on its edges), walked over the
cells of the mesh's grid the ray crosses (the grid lists every triangle within dhat + r),
for the capsule the capsule's own test. No iterate is beyond the first contact, so no
accepted state has the ball inside, however fast it moves.

On a prescribed motion (``catenet.terms.moving.Moving`` around the offset shape) the
obstacle jumps from its pose at t_n to that at t_n+1 at the start of a step; as for the
net's nodes, ``Moving.carry`` moves a ball it may reach rigidly with it, so the ball's
gap is kept. The ball's own contacts (the net nodes it touches, other balls) must then
come along, or the carried ball could swallow them: ``spread`` carries, by the same
rigid motion, every contact partner of a carried node through the ball barrier
(``catenet.terms.body.Ball``) whose gap is below SWEEP_SAFETY times the carried node's
displacement plus dhat, until no more come (a ball resting on carried net nodes comes
too). A partner left behind had a gap of at least twice the displacement plus dhat, so
it stays outside.
"""

from __future__ import annotations

import numpy as np

from catenet.terms.body import Ball

#: Nodes closer than SWEEP_SAFETY times the obstacle's largest displacement in a step
#: (plus the activation distance) ride with it into the step.
SWEEP_SAFETY = 2.0


def spread(terms, movers, start, base, trial, moved, t0: float, t1: float) -> int:
    """Carries the contact partners of carried nodes (``moved``: per node, the index in
    ``movers`` of the obstacle that carried it, -1: none), in ``base`` and ``trial`` in
    place, with that obstacle's rigid motion from t0 to t1; ``start`` is ``base`` before
    any carrying. Returns how many nodes came along."""
    balls = [t for t in terms if isinstance(t, Ball)]
    count = 0
    more = bool(balls) and bool((moved >= 0).any())
    while more:
        more = False
        for ball in balls:
            c, ends = ball.center, ball.nodes
            gap = np.linalg.norm(start[ends] - start[c], axis=1) - ball.radius
            if moved[c] >= 0:  # the ball came: the nodes it touches follow
                shift = float(np.linalg.norm(base[c] - start[c]))
                near = ends[(moved[ends] < 0) & (gap < SWEEP_SAFETY * shift + ball.dhat)]
                who = int(moved[c])
            else:  # a node it touches came: the ball follows
                shift = np.linalg.norm(base[ends] - start[ends], axis=1)
                pull = np.flatnonzero((moved[ends] >= 0) & (gap < SWEEP_SAFETY * shift + ball.dhat))
                near = np.array([c]) if pull.size else ends[:0]
                who = int(moved[ends[pull[0]]]) if pull.size else -1
            if near.size:
                moved[near] = who
                base[near] = movers[who].rigid(start[near], t0, t1)
                trial[near] = movers[who].rigid(trial[near], t0, t1)
                count += near.size
                more = True
    return count
