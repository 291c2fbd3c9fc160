"""Coupling rows (elements/couplings.py) through the builder: a coupler of three coordinates
over five bodies, two of its joints sharing a body (the row's bodies gathered once each), in
both evaluations (inline, mapped; numeric and over the model data d) against the same row
written here from the joints' coordinates as equations/coordinates.py reads them (the results'
joint state columns), and in the DAE residual's element sums against the inline residual."""

import numpy as np
import pytest

import casmech
from casmech.equations import readings
from casmech.equations.functions import build_functions, mapped_functions
from casmech.equations.readings import columns_function
from casmech.model import parametric
from casmech.model.lower import lower
from tests.helpers.equations import assert_mapped_residual_is_inline, dense, random_unit_p

C = (0.7, -1.3, 2.1)
IRRATIONAL = -1 / 2 ** 0.5  # no fraction of small denominator: g's row is linear
TEXT = f"""
casmech: 1
name: coupled
bodies:
  - {{name: a, mass: 1.0, inertia: [0.1, 0.2, 0.3], position: [0, 0, 0]}}
  - {{name: b, mass: 2.0, inertia: [0.3, 0.2, 0.4], position: [1, 0, 0]}}
  - {{name: c, mass: 1.5, inertia: [0.2, 0.2, 0.1], position: [0, 1, 0]}}
  - {{name: e, mass: 1.2, inertia: [0.2, 0.3, 0.1], position: [0, 2, 0]}}
joints:
  - {{name: ra, type: revolute, body_i: ground, body_j: a, at: [0, 0, 0], axis: [0, 0, 1]}}
  - {{name: cb, type: cylindrical, body_i: a, body_j: b, at: [1, 0, 0], axis: [1, 0, 0]}}
  - {{name: tc, type: translational, body_i: c, body_j: e, at: [0, 1.5, 0], axis: [0, 1, 1]}}
  - {{name: k, type: coupler, joints: [cb.displacement, ra, tc], coefficients: {list(C)}}}
  - {{name: g, type: coupler, joints: [cb.angle, ra], coefficients: [1.0, {IRRATIONAL}]}}
  - {{name: h, type: gear, joint_i: ra, joint_j: cb, ratio: -1.5}}
"""


def _rotation(p) -> np.ndarray:
    """A(p) of Euler parameters (written here: the homogeneous form)."""
    e0, e = p[0], p[1:]
    skew = np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])
    return (e0 ** 2 - e @ e) * np.eye(3) + 2 * np.outer(e, e) + 2 * e0 * skew


def _state(nb: int, rng):
    q = np.concatenate([rng.normal(size=3 * nb)] + [random_unit_p(rng) for _ in range(nb)])
    return rng.uniform(0, 2), q, rng.normal(size=7 * nb)


@pytest.mark.parametrize("which", ["inline", "mapped", "inline over d", "mapped over d"])
def test_coupling_rows_are_the_sums_of_the_joint_coordinates(which):
    model = casmech.loads(TEXT)
    ir = lower(model)
    split = parametric.split(ir)
    functions, extra = {
        "inline": (build_functions(ir).functions, []),
        "mapped": (mapped_functions(ir), []),
        "inline over d": (build_functions(split.ir, split.symbols).functions, [split.values]),
        "mapped over d": (mapped_functions(split.ir, split.symbols), [split.values]),
    }[which]
    states = columns_function(ir)  # the joint coordinates as the results write them
    names = readings.names(ir)
    rows = [j.rows[0] for j in ir.joints if j.couples]
    rng = np.random.default_rng(5)
    nb = ir.n_bodies
    for _ in range(3):
        t, q, q_dot = _state(nb, rng)
        # near the file's pose: the angles inside (-pi, pi), where the linear rows are smooth
        q[3 * nb:] = np.concatenate([p + 0.05 * rng.normal(size=4) for p in
                                     np.tile([1.0, 0, 0, 0], (nb, 1))])
        q[3 * nb:] = np.concatenate([p / np.linalg.norm(p) for p in q[3 * nb:].reshape(nb, 4)])
        s = dict(zip(names, dense(states(t, q, q_dot, np.zeros(7 * nb), np.zeros((3, 6)),
                                          np.zeros((3, 6)))).ravel(), strict=True))
        phi = dense(functions["phi"](t, q, *extra)).ravel()[rows]
        # coupler k has one angle (ra): C_ra rho sin(angle + (C_cb d_cb + C_tc d_tc) / C_ra),
        # rho the length of body a's x axis in the xy plane (1 where ra's rows hold: its
        # cosine and sine are dot products of the joint frames); g is linear in its angles;
        # the gear h (coefficients 1.5, 1: integers 3, 2) is (1.5 / 3) arg(z_ra^3 z_cb^2), z
        # the (cosine, sine) dot products of each joint's frames (ra: x, y on ground, x on a;
        # cb: y, z on a, y on b)
        shift = (C[0] * s["cb.displacement"] + C[2] * s["tc.displacement"]) / C[1]
        a, b = (_rotation(q[3 * nb + 4 * k:3 * nb + 4 * k + 4]) for k in (0, 1))
        rho = np.hypot(*a[:2, 0])
        z_ra = complex(a[0, 0], a[1, 0])
        z_cb = complex(a[:, 1] @ b[:, 1], a[:, 2] @ b[:, 1])
        want = [C[1] * rho * np.sin(s["ra.angle"] + shift),
                s["cb.angle"] + IRRATIONAL * s["ra.angle"], 0.5 * np.angle(z_ra ** 3 * z_cb ** 2)]
        # the same row from the coordinates of the results: round-off
        np.testing.assert_allclose(phi, want, rtol=1e-12, atol=1e-12, err_msg=which)
        # velocity level: phi_q q_dot is the rows' rate from the coordinates' rates
        rate = dense(functions["phi_q"](t, q, *extra) @ q_dot).ravel()[rows]
        want_rate = s["cb.angle_dot"] + IRRATIONAL * s["ra.angle_dot"]
        # the same rate, by the chain rule of the coordinates' AD: round-off
        np.testing.assert_allclose(rate[1], want_rate, rtol=1e-10, atol=1e-10, err_msg=which)


@pytest.mark.parametrize("form", ["rp", "romega"])
@pytest.mark.parametrize("kind", ["projection", "ggl"])
def test_coupling_rows_in_the_dae_residual_as_elements(form, kind):
    """The mapped DAE residual (a kernel per coupling over its bodies) equals the inline one."""
    ir = lower(casmech.loads(TEXT))
    assert_mapped_residual_is_inline(ir, form, kind)
