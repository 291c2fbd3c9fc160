"""ME751 driven pendulum against its closed form (issue 2 'must show').

theta(t) = pi/4 cos(2t) about global x, bar hanging along -z in the file:
CM r = (0, l sin(theta), -l cos(theta)) with l = L/2, driving torque
tau = I_O theta'' + m g l sin(theta), joint force on the bar F = m (r_ddot - g).
Mass and inertia are computed here from the bar's dimensions, not read from casmech.
"""

import numpy as np
import pytest

from tests.conftest import MODELS, run_model

L, W, RHO, G = 4.0, 0.05, 7800.0, 9.81
MASS = RHO * L * W * W
I_O = MASS * (L**2 + W**2) / 12 + MASS * (L / 2) ** 2  # about the pivot (x axis)


@pytest.fixture(scope="module")
def table():
    return run_model(MODELS / "me751_pendulum.yaml", t_end=10.0, output_step=0.01)[1]


def closed_form(t):
    th, thd, thdd = np.pi / 4 * np.cos(2 * t), -np.pi / 2 * np.sin(2 * t), -np.pi * np.cos(2 * t)
    arm = L / 2
    r = np.stack([0 * t, arm * np.sin(th), -arm * np.cos(th)])
    v = np.stack([0 * t, arm * np.cos(th) * thd, arm * np.sin(th) * thd])
    a = np.stack([0 * t, arm * (np.cos(th) * thdd - np.sin(th) * thd**2),
                  arm * (np.sin(th) * thdd + np.cos(th) * thd**2)])
    return th, thd, thdd, r, v, a


def test_motion_matches_closed_form(table):
    th, thd, thdd, r, v, a = closed_form(table["t"])
    for k, axis in enumerate("xyz"):
        # 1e-9 required by the issue; Newton stops at |Phi| <= 1e-12 on O(1) coordinates.
        np.testing.assert_allclose(table[f"bar.{axis}"], r[k], rtol=0, atol=1e-9)
        np.testing.assert_allclose(table[f"bar.v{axis}"], v[k], rtol=0, atol=1e-9)
        np.testing.assert_allclose(table[f"bar.a{axis}"], a[k], rtol=0, atol=1e-9)
    # Euler parameters of a rotation by theta about x: (cos(theta/2), sin(theta/2), 0, 0)
    np.testing.assert_allclose(table["bar.e0"], np.cos(th / 2), rtol=0, atol=1e-9)
    np.testing.assert_allclose(table["bar.e1"], np.sin(th / 2), rtol=0, atol=1e-9)
    np.testing.assert_allclose(table["bar.wx"], thd, rtol=0, atol=1e-9)
    np.testing.assert_allclose(table["bar.alphax"], thdd, rtol=0, atol=1e-9)
    for column in ("bar.wy", "bar.wz", "bar.alphay", "bar.alphaz"):
        np.testing.assert_allclose(table[column], 0, rtol=0, atol=1e-9)


def test_driving_torque_and_joint_force_match_closed_form(table):
    th, _, thdd, _, _, a = closed_form(table["t"])
    tau = I_O * thdd + MASS * G * (L / 2) * np.sin(th)
    # relative 1e-8 required by the issue; measured ~3e-12 (roundoff on 1e3 N m values)
    np.testing.assert_allclose(table["pivot.tx"], tau, rtol=1e-8, atol=1e-8 * np.max(abs(tau)))
    force = MASS * (a - np.array([0, 0, -G])[:, None])
    scale = np.max(np.abs(force))
    for k, axis in enumerate("xyz"):
        np.testing.assert_allclose(table[f"pivot.f{axis}"], force[k], rtol=1e-8, atol=1e-8 * scale)
    # a revolute about x transmits no torque about y or z for this planar motion
    np.testing.assert_allclose(table["pivot.ty"], 0, rtol=0, atol=1e-8 * scale)
    np.testing.assert_allclose(table["pivot.tz"], 0, rtol=0, atol=1e-8 * scale)


def test_constraints_hold_and_energy_balance(table):
    # Newton tolerance 1e-12
    assert np.max(table["constraint_violation"]) <= 1e-11
    # power of the driving torque = dE/dt (no other non-conservative forces)
    t, energy = table["t"], table["energy"]
    power = table["pivot.tx"] * table["bar.wx"]
    dedt = np.gradient(energy, t, edge_order=2)
    # central differences with h = 0.01 on E ~ 1e3 J varying at 2 rad/s: O(h^2 E''') ~ 1e-1 W
    np.testing.assert_allclose(dedt[1:-1], power[1:-1], rtol=0, atol=0.5)
