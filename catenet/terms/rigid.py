"""Free rigid bodies of any shape (a box, a capsule, a sphere, a closed mesh) in the
net's own implicit step: affine bodies on four nodes.

Formulation (affine body dynamics, Lan et al. 2022, in the lumped form that the net's
integrators already serve). A body's motion is y(X) = c + A (X - c0): its centre of mass
c and a 3x3 matrix A (the identity at t = 0, its pose there). For a mass m with second
moment J = int rho (X - c0)(X - c0)^T dV = tr(I)/2 1 - I (I the inertia tensor, both
about the centre of mass), the kinetic energy of that motion,

    T = m |c'|^2 / 2 + tr(A' J A'^T) / 2,

equals exactly that of four point masses m/4 at p_k = c + A Xbar_k, with
Xbar_k = sqrt(3/m) J^(1/2) v_k and v_k the unit vertices of a regular tetrahedron
(sum v_k = 0, sum v_k v_k^T = 4/3 1, so sum (m/4) Xbar_k = 0 and
sum (m/4) Xbar_k Xbar_k^T = J). A body is therefore four nodes of the net (no edges,
``Net.bodies`` trailing nodes) with lumped masses m/4: gravity (m g on c), the inertia
term of every integrator, restarts and trajectories treat them as any node, and the
incremental potential keeps its form (line search, the barrier's step cap and modified
Newton work unchanged). The pose is linear in the nodes: c = mean p_k and A = P^T B
(P the (4, 3) rows p_k, B = Xbar (Xbar^T Xbar)^-1, so that A Xbar_k = p_k - c).

Rigidity is the orthogonality energy ``Rigidity``: E = k |A^T A - 1|_F^2 / 2, zero for
every rotation, invariant under rigid motions (it exerts no net force or torque, so
momentum is exchanged only through contact), with k far above the loads' scale (the
body strains by about force x size / k). Compared with rotation-vector increments about
the current orientation, this keeps the mass matrix constant and diagonal, the Newmark
and implicit Euler updates as they are for nodes, and the angular momentum exchange
exact (the contact forces act at the points where they touch).

Turning within a Newton step. A step's straight path of the four nodes makes A linear in
the step length, A + t dA: a turn by an angle theta is its chord, which stretches the body
by about theta^2 / 2 on the way (A^T A - 1 grows with theta^2), so a step that turns far
sees the body as a stretched affine copy, its rigidity far from held. ``Rigidity`` is
therefore a term that bounds the step (``max_step``): no step moves a point of the body
by more than TURN_MAX times its distance from the centre (|t dA|_2 <= TURN_MAX, about a
turn of that many radians): the body turns by at most 0.25 rad per Newton iteration,
its stretch on the way within 3 %. A spin that a step cannot follow then takes several
iterations (or a shorter step), never one long chord. The contact's step cap is
conservative for any turn (the node's body-frame path is followed exactly, below), so
the turn bound is about the body staying a body, not about the barrier's guarantee.

Contact: ``BodyContact`` is a fixed shape's barrier term (``catenet.terms.shapes``,
``catenet.terms.contact``), built at the body's pose at t = 0, seeing every net node at
X = c0 + A^T (x - c) (the body frame; A^T = A^-1 for a rotation). Its energy
kappa b(d(X)) is a smooth function of the node and the four body nodes; the gradient and
Hessian are the shape's g_b, H_b through the Jacobian of X (module ``kernels`` of the
shape give those), the force on the net and on the body equal and opposite. The step cap
``max_step`` follows the quadratic body-frame path of every node by chords within
CA_SHARE of the smallest gap, each tested exactly against the shape grown by that much:
no iterate has a node inside the body.
"""

from __future__ import annotations

import math

import numpy as np

from catenet.kernels.rigid import (
    frame_state,
    rigidity_gradient,
    rigidity_hessian,
    rigidity_levels,
    rigidity_turn,
)
from catenet.terms.base import Term, register

#: Unit vertices of a regular tetrahedron (sum 0, sum v v^T = 4/3 1).
TETRA = np.array([[1.0, 1.0, 1.0], [1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0]])
TETRA /= math.sqrt(3.0)
CA_SHARE = 0.1  # the step cap's chords are within this share of the smallest gap
CA_ITER = 60  # pieces of the step cap (then the step is capped where they got)
TURN_MAX = 0.25  # the most a Newton step turns a body [rad] (|t dA|_2, module docstring)
EPS = np.finfo(np.float64).eps


def second_moment(inertia) -> np.ndarray:
    """J = tr(I)/2 1 - I: the second moment int rho r r^T of an inertia tensor I."""
    inertia = np.asarray(inertia, dtype=np.float64)
    return 0.5 * np.trace(inertia) * np.eye(3) - inertia


def inertia_problem(inertia) -> str | None:
    """Why ``inertia`` (3, 3) [kg m^2] is no rigid body's inertia tensor, else None."""
    tensor = np.asarray(inertia, dtype=np.float64)
    if tensor.shape != (3, 3) or not np.all(np.isfinite(tensor)):
        return "it is not a finite 3 x 3 matrix"
    scale = float(np.abs(tensor).max())
    if not scale > 0:
        return "it is zero"
    if not np.allclose(tensor, tensor.T, rtol=0, atol=1e-12 * scale):
        return "it is not symmetric"
    w = np.linalg.eigvalsh(tensor)
    if not w[0] > 1e-12 * scale:
        return f"it is not positive definite (principal moments {_show(w)})"
    if not w[0] + w[1] > w[2] * (1 + 1e-12):
        moments = _show(w)
        return f"its principal moments {moments} break I1 + I2 > I3 (no body has them)"
    return None


def _show(w) -> str:
    return "[" + ", ".join(f"{v:.6g}" for v in w) + "]"


class BodyFrame:
    """The four nodes ``first`` .. ``first + 3`` of a rigid body of ``mass`` [kg] whose
    world inertia at t = 0 is ``inertia`` (3, 3) [kg m^2] about its centre of mass
    ``center`` (see the module docstring)."""

    def __init__(self, first: int, mass: float, inertia, center):
        self.nodes = first + np.arange(4, dtype=np.int64)
        self.mass = float(mass)
        self.center = np.asarray(center, dtype=np.float64).copy()
        J = second_moment(inertia)
        w, Q = np.linalg.eigh(J)
        self.points = math.sqrt(3.0 / self.mass) * TETRA @ (Q * np.sqrt(w)) @ Q.T  # (4, 3)
        self.B = self.points @ np.linalg.inv(self.points.T @ self.points)  # (4, 3)
        T = np.empty((4, 4))
        T[0] = 0.25
        T[1:] = self.B.T
        self.T = T  # (c, a1, a2, a3) = T (p0, p1, p2, p3), per axis
        self.reach = float(np.linalg.norm(self.points, axis=1).max())

    def place(self, velocity=None, angular_velocity=None):
        """The nodes' positions (4, 3) at t = 0 and velocities (4, 3) for the centre's
        ``velocity`` and the ``angular_velocity`` (world frame)."""
        v = np.zeros(3) if velocity is None else np.asarray(velocity, dtype=np.float64)
        w = np.zeros(3) if angular_velocity is None else np.asarray(angular_velocity, float)
        return self.center + self.points, v + np.cross(w, self.points)

    def state(self, x):
        """(c, A) of the positions x (N, 3) (or the rates of velocities v)."""
        return frame_state(np.asarray(x, dtype=np.float64), self.nodes, self.B)

    def pose(self, x):
        """(c, R): the centre and the rotation from the pose at t = 0 (the nearest
        rotation to A, by its polar decomposition)."""
        c, A = self.state(x)
        U, _, Vt = np.linalg.svd(A)
        R = U @ Vt
        if np.linalg.det(R) < 0:
            R = U @ np.diag([1.0, 1.0, -1.0]) @ Vt
        return c, R

    def motion(self, x, v):
        """(velocity, angular velocity) of the centre and the body (world frame)."""
        _, A = self.state(x)
        cdot, Adot = self.state(v)
        W = Adot @ np.linalg.inv(A)
        return cdot, 0.5 * np.array([W[2, 1] - W[1, 2], W[0, 2] - W[2, 0], W[1, 0] - W[0, 1]])

    def momentum(self, x, v):
        """(linear, angular about the origin) momentum of the body's four nodes."""
        P, V = np.asarray(x)[self.nodes], np.asarray(v)[self.nodes]
        m = 0.25 * self.mass
        return m * V.sum(axis=0), m * np.cross(P, V).sum(axis=0)

    def chain(self) -> np.ndarray:
        """kron(T, 1_3) (12, 12): the body's (c, a1, a2, a3) from its nodes' DOFs."""
        return np.kron(self.T, np.eye(3))

    def dofs(self) -> np.ndarray:
        return (3 * self.nodes[:, None] + np.arange(3)).ravel()


def _dense_pattern(dofs_a, dofs_b):
    rows = np.repeat(dofs_a, len(dofs_b))
    cols = np.tile(dofs_b, len(dofs_a))
    return rows, cols


@register("rigidity")
class Rigidity(Term):
    """E = k |A^T A - 1|_F^2 / 2 on the body ``frame`` (k [J])."""

    role = "internal"
    convex = False  # positive semidefinite on the rotations, not everywhere
    bounds_step = True  # the body's turn per Newton step (``max_step``)
    structural = True  # the body's own: its force (round-off) is no contact with the net

    def __init__(self, frame: BodyFrame, k: float, *, n_nodes: int):
        if not (math.isfinite(k) and k > 0):
            raise ValueError(f"rigidity: k = {k!r}: must be > 0")
        self.frame, self.k, self.n_nodes = frame, float(k), int(n_nodes)
        D = np.zeros((9, 12))  # d vec(A) (row-major) / d P (node-major)
        for row in range(3):
            for m in range(3):
                for k4 in range(4):
                    D[3 * row + m, 3 * k4 + row] = frame.B[k4, m]
        self._D = D
        self._b_sum = float(np.abs(frame.B).sum(axis=0).max())  # (roundoff's constants)
        self._b_norm = float(np.linalg.norm(frame.B))

    def pattern(self):
        d = self.frame.dofs()
        return _dense_pattern(d, d)

    def _C(self, x):
        _, A = self.frame.state(x)
        return A, A.T @ A - np.eye(3)

    def energy(self, x):
        _, C = self._C(x)
        return 0.5 * self.k * float(np.sum(C * C))

    def gradient(self, x, grad):
        return float(rigidity_gradient(x, self.frame.nodes, self.frame.B, self.k, grad))

    def hessian(self, x, values):
        # vec(A) row-major (index 3 l + m); column (l, m) of M: vec(dC) for dA = E_lm,
        # dC_ij = E^T A + A^T E = delta_im A_lj + A_li delta_jm; H = M^T M + 2 kron(1, C)
        # (C:(dA^T dA) = sum_l dA_lm C_mm' dA_lm'), chained to the nodes by D
        rigidity_hessian(x, self.frame.nodes, self.frame.B, self.k, self._D, values)
        return True

    def roundoff(self, x, energy):
        """A carries an error of eps |p| sum|B| (positions of size |p| times B's
        weights), C twice that, and the gradient 2 k B A C turns it into forces: the
        levels without the factor eps that the solver applies."""
        spread, a_max, c_max = rigidity_levels(
            np.asarray(x, dtype=np.float64), self.frame.nodes, self.frame.B
        )
        spread *= self._b_sum
        level = 8.0 * self.k * self._b_norm * spread * max(1.0, a_max) ** 2
        return level, abs(energy) + 2.0 * self.k * c_max * spread

    def stiffness(self):
        s = np.zeros(self.n_nodes)
        s[self.frame.nodes] = self.k / self.frame.reach**2
        return s

    def max_step(self, x, dx) -> float:
        """The longest multiple t of the step dx that turns the body by at most TURN_MAX:
        |t dA|_2 <= TURN_MAX (no point of the body moves by more than TURN_MAX times its
        distance from the centre, relative to the centre); inf for a translation."""
        turn = float(
            rigidity_turn(np.asarray(dx, dtype=np.float64), self.frame.nodes, self.frame.B)
        )
        return TURN_MAX / turn if turn > 0.0 else math.inf
