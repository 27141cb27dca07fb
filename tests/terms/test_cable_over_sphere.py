"""A cable hanging over a fixed frictionless sphere against its closed form.

A cable of length L and weight w per length, both ends pinned at (+-X, 0, z_s), hangs
symmetrically over a sphere of radius R centred at the origin. On a frictionless surface
the tension obeys dT/ds = w dz/ds along the whole cable, the wrapped part lies on the
great circle y = 0 from the top to the tangent points at angle phi from the top,
P = (R sin phi, R cos phi), and each free span is a catenary z = c + a cosh((x - x0)/a)
tangent to the sphere at P (slope -tan phi), with horizontal tension H = w a:

    x0 = x_P + a asinh(tan phi),        c = z_P - a cosh(asinh(tan phi)),
    z_s = c + a cosh((X - x0)/a),       L = 2 R phi + 2 a (sinh((X - x0)/a) + tan phi),

two equations for phi and a (fsolve). The discrete cable rests on its barrier gap g
(below dhat), so it wraps a sphere of radius R + g: the closed form is taken with R plus
the mean gap of the nodes in contact. With dhat refined alongside the edges (dhat ~ 1/n),
H and the free span's shape converge to the closed form at second order in the edge
length (the lumped weight of a catenary).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import fsolve

from catenet.model.net import Loads, Net
from catenet.scene import Scene
from catenet.solver.path import Settings, solve
from catenet.terms.contact import SphereBarrier, default_stiffness

X, Z_S, LENGTH, W = 2.0, 0.0, 5.0, 1.0


def closed_form(R: float):
    """phi, a, x_P, x0, c of the cable over a sphere of radius R."""

    def parts(p):
        phi, a = p
        u = math.asinh(math.tan(phi))
        x_p, z_p = R * math.sin(phi), R * math.cos(phi)
        return x_p, x_p + a * u, z_p - a * math.cosh(u)

    def equations(p):
        phi, a = p
        _, x0, c = parts(p)
        return [
            c + a * math.cosh((X - x0) / a) - Z_S,
            2 * R * phi + 2 * a * (math.sinh((X - x0) / a) + math.tan(phi)) - LENGTH,
        ]

    (phi, a), info, ok, _ = fsolve(equations, [1.0, 0.5], xtol=1e-13, full_output=True)
    assert ok == 1 and np.abs(info["fvec"]).max() < 1e-12
    return (phi, a, *parts((phi, a)))


def closed_shape(R: float, n: int) -> np.ndarray:
    """n points of the closed form, evenly spaced by arc length."""
    phi, a, x_p, x0, c = closed_form(R)
    out = np.zeros((n, 3))
    for k, s in enumerate(np.linspace(-LENGTH / 2, LENGTH / 2, n)):
        q, side = abs(s), math.copysign(1.0, s)
        if q <= R * phi:
            out[k] = [side * R * math.sin(q / R), 0.0, R * math.cos(q / R)]
        else:
            x = x0 + a * math.asinh((q - R * phi) / a + math.sinh((x_p - x0) / a))
            out[k] = [side * x, 0.0, c + a * math.cosh((x - x0) / a)]
    return out


def hang(n: int):
    """The static equilibrium of the n-node cable over the unit sphere (dhat = 0.05 /
    n), started 2 dhat outside the closed-form shape; its errors against the closed form:
    H, and the largest vertical distance of the free spans' nodes from the catenary."""
    R, dhat = 1.0, 0.05 / n
    nodes = closed_shape(R + 2 * dhat, n)
    nodes[0], nodes[-1] = [-X, 0.0, Z_S], [X, 0.0, Z_S]
    edges = np.column_stack([np.arange(n - 1), np.arange(1, n)])
    net = Net.from_arrays(
        nodes, edges, EA=1e7, fixed=[0, n - 1], rest_length=LENGTH / (n - 1), line_density=W / 9.81
    )
    free = np.flatnonzero(~net.fixed)
    ball = SphereBarrier(
        free, [0, 0, 0], R, kappa=default_stiffness(W * LENGTH / n, dhat), dhat=dhat
    )
    r = solve(Scene(net, Loads(gravity=np.array([0, 0, -9.81])), (ball,)), Settings(rtol=1e-10))
    assert r.converged
    gap = ball.gap(r.x)
    assert gap.min() > 0.0
    phi, a, x_p, x0, c = closed_form(R + float(np.mean(gap[gap < dhat])))
    assert abs(r.reaction[0, 0] + r.reaction[-1, 0]) < 1e-6  # symmetric
    assert np.abs(r.x[:, 1]).max() < 1e-9  # in the plane of the great circle
    span = np.flatnonzero((np.abs(r.x[:, 0]) > x_p) & ~net.fixed)
    catenary = c + a * np.cosh((np.abs(r.x[span, 0]) - x0) / a)
    return abs(r.reaction[-1, 0] / (W * a) - 1), float(np.abs(r.x[span, 2] - catenary).max())


def test_a_cable_over_a_sphere_converges_to_the_tangent_catenaries_at_second_order():
    phi, a, x_p, x0, c = closed_form(1.0)
    assert 0.9 < phi < 1.3 and a > math.cos(phi) ** 2  # a real wrap, pressed on throughout
    errors = [hang(n) for n in (51, 101, 201)]
    for (h_coarse, z_coarse), (h_fine, z_fine) in zip(errors, errors[1:], strict=False):
        assert h_fine < h_coarse / 3 and z_fine < z_coarse / 3  # 4 at second order
    h_err, z_err = errors[-1]
    assert h_err < 3e-4 and z_err < 1.5e-4  # of H, and of R = 1 m
