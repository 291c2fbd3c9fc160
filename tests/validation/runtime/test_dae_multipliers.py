"""The multipliers of r-p / r-omega dynamics rows (reactions and a driver's actuation) are solved
at each row's state (runtime.dae_rows.solve), so they are as accurate as the state: against
inverse dynamics of the same motion, the joint formulation, and the closed form of a driven
block whose Coulomb friction reverses between two output rows."""

from __future__ import annotations

import numpy as np
import pytest

import casmech
from casmech.api import results_table
from tests.conftest import MODELS

CRANK_JOINTS = ("crank_pivot", "crank_pin", "wrist_pin", "slide")
COMPONENTS = ("fx", "fy", "fz", "tx", "ty", "tz")

BLOCK = """casmech: 1
name: driven_block
parameters: {{m: 2.0, A: 0.1, w: 3.0, Fc: 1.5}}
gravity: [0, 0, 0]
bodies:
  - {{name: block, mass: m, inertia: [0.1, 0.1, 0.1], position: [0, 0, 0]}}
joints:
  - name: slide
    type: translational
    body_i: ground
    body_j: block
    at: [0, 0, 0]
    axis: [1, 0, 0]
    driver: {{displacement: A * sin(w * t)}}
    friction: {{coulomb: Fc}}
analysis: {{type: dynamics, t_end: 1.0, output_step: 0.01, rtol: {rtol}, atol: 1.0e-12,
           formulation: {formulation}}}
"""


def _columns(functions, result) -> dict[str, np.ndarray]:
    names, values = results_table(functions, result)
    return dict(zip(names, values.T, strict=True))


@pytest.fixture(scope="module")
def crank():
    """The driven slider-crank over 0.5 s (a half turn): inverse dynamics, and dynamics in
    each formulation at rtol 1e-10."""
    functions = casmech.compile(casmech.load(MODELS / "slider_crank.yaml"))
    runs = {"inverse": casmech.analyze(functions, analysis="inverse_dynamics", t_end=0.5)}
    for name in ("rp", "romega", "joint"):
        runs[name] = casmech.analyze(functions, analysis="dynamics", formulation=name,
                                     t_end=0.5, rtol=1e-10, atol=1e-12)
    return {name: _columns(functions, result) for name, result in runs.items()}


def _reactions(columns: dict[str, np.ndarray]) -> np.ndarray:
    return np.array([columns[f"{joint}.{c}"] for joint in CRANK_JOINTS for c in COMPONENTS])


@pytest.mark.parametrize("formulation", ["rp", "romega"])
def test_a_driven_slider_cranks_actuation_and_reactions_are_inverse_dynamics(crank, formulation):
    """The motion is fully driven, so dynamics and inverse dynamics are one motion: the crank
    torque and every reaction agree to the state's accuracy."""
    rows, reference = crank[formulation], crank["inverse"]
    np.testing.assert_allclose(rows["t"], reference["t"], rtol=0, atol=1e-12)  # one grid
    scale = np.abs(_reactions(reference)).max()
    # the rows' multipliers are an exact solve at states within ~rtol 1e-10 of the motion;
    # 1e-8 of the largest reaction leaves 100x for the condition of that solve
    np.testing.assert_allclose(rows["crank_pivot.tz"], reference["crank_pivot.tz"], rtol=0,
                               atol=1e-8 * np.abs(reference["crank_pivot.tz"]).max())
    np.testing.assert_allclose(_reactions(rows), _reactions(reference), rtol=0,
                               atol=1e-8 * scale)  # as above, every joint's six columns


@pytest.mark.parametrize("formulation", ["rp", "romega"])
def test_a_driven_slider_cranks_reactions_are_the_joint_formulations(crank, formulation):
    scale = np.abs(_reactions(crank["joint"])).max()
    # two integrations of one motion at rtol 1e-10; the joint formulation's own reactions are
    # within 1e-7 of inverse dynamics (its multipliers come from its own integration)
    np.testing.assert_allclose(_reactions(crank[formulation]), _reactions(crank["joint"]),
                               rtol=0, atol=1e-7 * scale)


@pytest.mark.parametrize("formulation", ["rp", "romega"])
@pytest.mark.parametrize("rtol", [1e-6, 1e-10])
def test_a_driven_blocks_force_is_the_closed_form_also_right_after_the_friction_reverses(
        formulation, rtol):
    """x = A sin(w t) driven, Coulomb friction Fc: the driver's force on the block is
    m x_ddot + Fc sign(x_dot) at every row. The rate reverses at t = pi / (2 w) = 0.5236,
    between the rows 0.52 and 0.53, within one of the integrator's steps."""
    m, amplitude, w, coulomb = 2.0, 0.1, 3.0, 1.5
    functions = casmech.compile(casmech.loads(BLOCK.format(rtol=rtol, formulation=formulation)))
    rows = _columns(functions, casmech.analyze(functions))
    t = rows["t"]
    force = (m * -amplitude * w**2 * np.sin(w * t)
             + coulomb * np.sign(amplitude * w * np.cos(w * t)))
    assert np.any(np.diff(np.sign(rows["slide.displacement_dot"])) != 0)  # it reverses
    # the reaction is what the joint exerts on the block, the driving force with it. The
    # driven state is exact, so is the solve at it: roundoff of one body's small system
    np.testing.assert_allclose(rows["slide.fx"], force, rtol=0, atol=1e-12)
