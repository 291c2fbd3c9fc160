"""Andrews' squeezing mechanism (the Test Set for IVP Solvers of Bari; Hairer & Wanner, Solving
ODEs II, sec. VII.7) against the test set's reference solution at t = 0.03 (provenance:
tests/reference/README.md). Seven bodies in the plane, a driving torque, a stiff spring;
accelerations up to 1e4..1e6 rad/s^2 and angular rates reaching 1.4e3 rad/s within 0.03 s."""

import csv

import numpy as np
import pytest

import casmech
from tests.conftest import Table
from tests.helpers.reference_data import REFERENCE, VALIDATION_MODELS

MODEL = VALIDATION_MODELS / "andrews_squeezer.yaml"
ANGLES = ("beta", "theta", "gamma", "phi", "delta", "omega", "epsilon")


def reference() -> dict[str, float]:
    with open(REFERENCE / "bari" / "andrews_t0.03.csv") as handle:
        rows = csv.DictReader(line for line in handle if not line.startswith("#"))
        return {row["name"]: float(row["value"]) for row in rows}


def squeezer_angles(table: Table) -> tuple[np.ndarray, np.ndarray]:
    """The test set's seven angles and their rates over the rows, from the bodies' absolute
    angles about z (2 atan2(e3, e0), unwrapped) and rates wz: body 1 beta, 2 beta + theta,
    3 gamma, 4 phi + delta, 5 delta, 6 omega + epsilon, 7 epsilon."""
    body = [np.unwrap(2 * np.arctan2(table[f"body{k}.e3"], table[f"body{k}.e0"]))
            for k in range(1, 8)]
    rate = [table[f"body{k}.wz"] for k in range(1, 8)]

    def relative(a):
        return np.array([a[0], a[1] - a[0], a[2], a[3] - a[4], a[4], a[5] - a[6], a[6]])

    return relative(body), relative(rate)


@pytest.mark.parametrize("stabilization", ["ggl", "projection", None])
@pytest.mark.parametrize("rtol", [1e-6, 1e-8, 1e-10])
def test_squeezer_matches_the_reference_through_the_dae(rtol, stabilization):
    """Through IDAS on a DAE (no fallback to the augmented-Lagrangian steps): the r-p DAE with
    either stabilization, and (None: formulation auto) the joint DAE, or the r-p DAE after it
    when the joint DAE's corrector fails (at t ~ 0.02 s from rtol 1e-10 on; measured
    2026-11-24: within 1.8e-10 m of the r-p DAE's positions where it passes). The angles at
    t = 0.03 within 100 rtol of the largest (|beta| = 15.8 rad), and the rates within 300 rtol
    of the largest (|theta_dot| = 1424 rad/s). Measured (rtol 1e-6, 1e-8, 1e-10): angles
    3.2e-6, 2.6e-6, 5.8e-8 rad with ggl, 5.6e-5, 7.2e-7, 1.2e-8 with projection; an
    independent solver (DOP853 on the test set's own equations) is 2.6e-7 off at rtol 1e-10
    and 4.1e-8 at rtol 1e-12. The rates of bodies 3-7 follow from bodies 1-2 through the
    loops, ~20 times more sensitive to the angles (relative rate error / angle error, at rtol
    1e-10 to 1e-12): 2.3e-5 rad/s = 160 rtol |theta_dot| with ggl at rtol 1e-10."""
    functions = casmech.compile(casmech.load(MODEL))
    result = casmech.analyze(functions, rtol=rtol, atol=rtol / 100,
                             stabilization=stabilization)
    assert result.metadata["integrator"] == "idas"
    assert result.metadata.get("augmented_from") is None
    if stabilization is not None:
        assert result.metadata["formulation"] == "rp"
    elif rtol >= 1e-8:
        assert result.metadata["formulation"] == "joint"
    else:
        assert result.metadata["formulation"] == "joint" or "the joint DAE failed" in \
            result.metadata["formulation_fallback"]
    table = Table(*casmech.results_table(functions, result))
    assert table["t"][-1] == pytest.approx(0.03)
    angles, rates = squeezer_angles(table)
    expected = reference()
    want = np.array([expected[name] for name in ANGLES])
    want_rates = np.array([expected[f"{name}_dot"] for name in ANGLES])
    error = np.abs(angles[:, -1] - want)
    print(f"\nrtol {rtol:g} {stabilization}: angle errors {np.array2string(error, precision=1)}, "
          f"{result.metadata.get('idas_steps', result.metadata.get('steps'))} IDAS steps")
    np.testing.assert_allclose(angles[:, -1], want, rtol=0, atol=100 * rtol * np.max(np.abs(want)))
    np.testing.assert_allclose(rates[:, -1], want_rates, rtol=0,
                               atol=300 * rtol * np.max(np.abs(want_rates)))
