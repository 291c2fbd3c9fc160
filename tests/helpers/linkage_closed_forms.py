"""Closed-form kinematics of planar linkages, as CasADi expressions of time.

Independent of casmech: each mechanism's position is written from its loop-closure geometry;
velocities and accelerations are the exact time derivatives (CasADi AD of these formulas).
"""

import casadi as ca
import numpy as np

T = ca.SX.sym("t")


def _derivatives(expressions: dict):
    """name -> (value, d/dt, d2/dt2) functions of t, evaluated on arrays."""
    out = {}
    for name, expr in expressions.items():
        d1 = ca.jacobian(expr, T)
        d2 = ca.jacobian(d1, T)
        f = ca.Function("closed_form", [T], [expr, d1, d2])
        out[name] = lambda t, f=f: [np.array(v).ravel() for v in f.map(len(t))(np.atleast_2d(t))]
    return out


def slider_crank(a, b, omega):
    th = omega * T
    x_pin, y_pin = a * ca.cos(th), a * ca.sin(th)
    x_slider = x_pin + ca.sqrt(b**2 - y_pin**2)
    rod_angle = ca.atan2(-y_pin, x_slider - x_pin)
    return _derivatives({
        "crank.x": x_pin / 2, "crank.y": y_pin / 2, "crank.angle": th,
        "rod.x": (x_pin + x_slider) / 2, "rod.y": y_pin / 2, "rod.angle": rod_angle,
        "slider.x": x_slider,
    })


def four_bar(a, b, c, d, omega, theta0=np.pi / 2):
    th = theta0 + omega * T
    bx, by = a * ca.cos(th), a * ca.sin(th)
    e = ca.sqrt((d - bx) ** 2 + by**2)
    beta = ca.atan2(-by, d - bx)
    alpha = ca.acos((b**2 + e**2 - c**2) / (2 * b * e))  # open assembly: + alpha
    cx, cy = bx + b * ca.cos(beta + alpha), by + b * ca.sin(beta + alpha)
    return _derivatives({
        "crank.x": bx / 2, "crank.y": by / 2, "crank.angle": th,
        "coupler.x": (bx + cx) / 2, "coupler.y": (by + cy) / 2,
        "coupler.angle": ca.atan2(cy - by, cx - bx),
        "rocker.x": (d + cx) / 2, "rocker.y": cy / 2, "rocker.angle": ca.atan2(cy, cx - d),
    })
