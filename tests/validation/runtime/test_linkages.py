"""Slider-crank and four-bar kinematics and inverse dynamics against closed forms."""

import numpy as np
import pytest

from tests.conftest import MODELS, run_model
from tests.helpers import linkage_closed_forms as closed_forms

# Newton converges to |Phi| <= 1e-12 on O(1) lengths; velocity/acceleration solves add
# roundoff proportional to the condition number of Phi_q (~1e2 here): 1e-9 leaves margin.
ATOL = 1e-9

CASES = {
    "slider_crank": (closed_forms.slider_crank(0.5, 2.0, 2 * np.pi), ("crank", "rod", "slider")),
    "four_bar": (closed_forms.four_bar(0.5, 2.0, 1.5, 2.0, np.pi), ("crank", "coupler", "rocker")),
}


@pytest.fixture(scope="module", params=sorted(CASES))
def case(request):
    functions, table = run_model(MODELS / f"{request.param}.yaml", t_end=2.0, output_step=0.01)
    reference, bodies = CASES[request.param]
    return functions, table, reference, bodies


def test_positions_velocities_accelerations(case):
    _, table, reference, _ = case
    t = table["t"]
    for name, exact in reference.items():
        body, quantity = name.split(".")
        value, rate, acceleration = exact(t)
        if quantity == "angle":  # planar rotation about z: compare rates only (angles wrap)
            np.testing.assert_allclose(table[f"{body}.wz"], rate, rtol=0, atol=ATOL)
            np.testing.assert_allclose(table[f"{body}.alphaz"], acceleration, rtol=0, atol=1e-8)
            continue
        np.testing.assert_allclose(table[name], value, rtol=0, atol=ATOL)
        np.testing.assert_allclose(table[f"{body}.v{quantity}"], rate, rtol=0, atol=ATOL)
        # accelerations reach ~1e2 m/s^2 (omega^2 a with omega = 2 pi): 1e-8 absolute
        np.testing.assert_allclose(table[f"{body}.a{quantity}"], acceleration, rtol=0, atol=1e-8)


def test_motion_stays_planar(case):
    _, table, _, bodies = case
    for body in bodies:
        for column in ("z", "vz", "az", "wx", "wy"):
            np.testing.assert_allclose(table[f"{body}.{column}"], 0, rtol=0, atol=ATOL)


def test_driver_power_equals_rate_of_energy(case):
    """Inverse dynamics: the crank torque's power equals dE/dt of the whole linkage, computed
    from each body's mass, inertia and the motion (no friction, no other actuators)."""
    functions, table, _, bodies = case
    power_in = table["crank_pivot.tz"] * table["crank.wz"]
    rate = np.zeros_like(power_in)
    gravity = functions.ir.gravity
    for k, body in enumerate(bodies):
        spec = functions.ir.bodies[k]
        v = np.stack([table[f"{body}.v{c}"] for c in "xyz"], axis=1)
        a = np.stack([table[f"{body}.a{c}"] for c in "xyz"], axis=1)
        w = np.stack([table[f"{body}.w{c}"] for c in "xyz"], axis=1)
        alpha = np.stack([table[f"{body}.alpha{c}"] for c in "xyz"], axis=1)
        # planar motion about z: J_global w = Izz w (the body's z axis stays global z)
        rate += spec.mass * np.einsum("ij,ij->i", v, a - gravity)
        rate += spec.inertia[2, 2] * w[:, 2] * alpha[:, 2]
    scale = np.max(np.abs(power_in))
    # both sides are exact expressions of the same states; roundoff only
    np.testing.assert_allclose(power_in, rate, rtol=0, atol=1e-9 * scale)
