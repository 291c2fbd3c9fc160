"""What an FMU exposes of a model (casmech.fmu.model), without building it: parameters by kind
and the inputs."""

import numpy as np

import casmech
from casmech.fmu.model import exported
from tests.helpers.fmu import MODELS


def kinds(model) -> dict[str, str]:
    return {p.name: p.kind for p in exported(model).parameters}


def test_a_count_is_structural_an_initial_velocity_fixed_a_mass_tunable():
    assert kinds(casmech.load(MODELS / "chain_repeat.yaml")) == {
        "N": "structural", "L": "fixed", "w0": "fixed", "m": "tunable", "w": "tunable"}


def test_parameters_defined_from_others_are_calculated():
    found = kinds(casmech.load(MODELS / "four_bar.yaml"))
    assert {n for n, k in found.items() if k == "calculated"} == {
        "bo4", "beta", "alpha", "Cx", "Cy", "phi3", "phi4"}
    assert found["omega"] == "tunable"  # the crank driver's speed: not the start pose
    assert found["a"] == "fixed"


def test_calculated_parameters_follow_the_independent_ones():
    """Cx of the four-bar at d = 2.5, as the model's own evaluation at --set d=2.5."""
    import casadi as ca

    view = exported(casmech.load(MODELS / "four_bar.yaml"))
    free = [p for p in view.parameters if p.kind in ("fixed", "tunable")]
    values = [2.5 if p.name == "d" else p.value for p in free]
    calculated = ca.Function("c", [view.theta], [view.calculated])(values)
    names = [p.name for p in view.parameters if p.kind == "calculated"]
    again = casmech.load(MODELS / "four_bar.yaml", {"d": "2.5"})
    # the same formula evaluated by CasADi and by the schema's NumPy: round-off apart
    np.testing.assert_allclose(float(calculated[names.index("Cx")]), again.parameters["Cx"],
                               rtol=1e-14, atol=0)
    assert abs(again.parameters["Cx"] - casmech.load(MODELS / "four_bar.yaml").parameters["Cx"]
               ) > 1e-3  # d mattered


def test_effort_motors_and_controls_are_the_inputs():
    model = casmech.load(MODELS / "ocp_double_pendulum_swing_up.yaml")
    view = exported(model)
    assert [i.name for i in view.inputs] == [f"{c.joint}.{c.type}" for c in model.ocp.controls]
    assert exported(model, ["none"]).inputs == ()
