"""The motor and table examples of models/ against closed forms and the power balance: a
driven mechanism's energy (kinetic + gravity + springs) changes by the work of its drivers,
E(t) - E(0) = integral of (driving torque x angular rate + driving force x slide rate), the
drivers' torques and forces read from the joints' reaction columns."""

from __future__ import annotations

import numpy as np
from scipy.integrate import cumulative_simpson

import casmech
from tests.conftest import MODELS, Table

CSV = MODELS / "table_driver_profile.csv"


def run(name: str, **settings) -> Table:
    functions = casmech.compile(casmech.load(MODELS / f"{name}.yaml"))
    return Table(*casmech.results_table(functions, casmech.analyze(functions, **settings)))


def power_balance(table: Table, power: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(E(t) - E(0), the drivers' work from 0 to t by Simpson's rule) at every output."""
    energy = table["energy"]
    return energy - energy[0], cumulative_simpson(power, x=table["t"], initial=0.0)


def test_motor_crank_angle_and_power():
    table = run("motor_crank", t_end=0.8, output_step=0.001)
    t = table["t"]
    theta = np.unwrap(np.arctan2(-table["crank.z"], table["crank.x"]))  # about +y from +x
    after = t >= 0.5
    # the integral of omega * step(t, 0, 0, 0.5, 1) is omega (t - 0.25) after the ramp; the
    # speed motor is a position-level driver: measured 2e-15 rad
    np.testing.assert_allclose(theta[after], 4 * np.pi * (t[after] - 0.25), rtol=0, atol=1e-10)
    change, work = power_balance(table, table["crank_pivot.ty"] * table["crank.wy"])
    # Simpson at h = 1 ms on a power of up to 850 W: measured 8.1e-7 J of 72 J
    np.testing.assert_allclose(change, work, rtol=0, atol=1e-5)


def test_table_driver_follows_its_profile_and_power():
    table = run("table_driver", t_end=2.0, output_step=0.0025)
    samples = np.loadtxt(CSV, delimiter=",", comments="#", skiprows=4)
    lift = table["plunger.z"] - table["plunger.z"][0]
    for k in (0, 1):  # two cam revolutions: the spline passes through every sample
        at = np.searchsorted(table["t"], samples[:, 0] + k - 1e-9)
        # interpolation is exact at the samples: measured 1e-16 m
        np.testing.assert_allclose(lift[at], samples[:, 1], rtol=0, atol=1e-12)
    power = table["lift.fz"] * table["plunger.vz"] + table["cam_shaft.tz"] * table["cam.wz"]
    change, work = power_balance(table, power)
    # Simpson at h = 2.5 ms: measured 9.7e-8 J of 0.88 J
    np.testing.assert_allclose(change, work, rtol=0, atol=1e-5)
