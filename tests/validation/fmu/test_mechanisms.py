"""FMUs of mechanisms with loops, of an arm imported from a URDF and of a spinning top (a
quaternion among the states), simulated by fmpy against `casmech run` (slow: each builds
for about 10 s)."""

import pytest
import yaml as yaml_module

import casmech
from casmech.cli import main
from tests.helpers.fmu import MODELS, ROOT, assert_matches, build, reference, simulate

pytestmark = pytest.mark.slow
KINDS = ("ModelExchange", "CoSimulation")


def free_four_bar(overrides=None):
    """The gallery's four-bar with its crank free and gravity in its plane: one degree of
    freedom through a loop (the universal joint is cut)."""
    text = (MODELS / "four_bar.yaml").read_text()
    free = text.replace("    driver:\n      angle: omega * t\n", "").replace(
        "bodies:\n", "gravity: [0, -9.81, 0]\n\nbodies:\n", 1).replace(
        "type: inverse_dynamics", "type: dynamics")
    assert free.count("gravity") == 1 and "angle: omega" not in free
    return casmech.loads(free, str(MODELS / "four_bar_free.yaml"), overrides)


@pytest.fixture(scope="module")
def four_bar(toolchain, tmp_path_factory):
    return build(free_four_bar(), tmp_path_factory.mktemp("fmu"), toolchain, "four_bar")


@pytest.mark.parametrize("kind", KINDS)
def test_a_four_bar_moves_through_its_loop_as_casmech_runs_it(four_bar, kind):
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(four_bar)) == []
    got = simulate(four_bar, kind)
    assert_matches(got, reference(free_four_bar()))
    assert got["constraint_violation"] < 1e-7  # the projections keep the loop closed


@pytest.mark.parametrize("kind", KINDS)
def test_a_new_crank_length_closes_the_loop_anew(four_bar, kind):
    """`a` moves the start pose of the coupler and rocker (their file positions are
    computed from it): the FMU solves the closest closed pose again, as `--set a=0.6` does."""
    from fmpy import simulate_fmu

    changed = {"a": 0.6, "m": 1.5}
    model = free_four_bar({k: str(v) for k, v in changed.items()})
    assert_matches(simulate(four_bar, kind, start_values=changed), reference(model))
    # a calculated parameter follows: the coupler pin's y from the loop closure's formula
    calculated = simulate_fmu(str(four_bar), fmi_type=kind, stop_time=0.01, output=["Cy"],
                              start_values=changed)
    assert abs(calculated["Cy"][-1] - model.parameters["Cy"]) < 1e-14  # round-off


def test_the_driven_four_bar_follows_its_crank(toolchain, tmp_path):
    """The gallery's four-bar (no degree of freedom: the crank angle is prescribed), as
    `casmech run --analysis dynamics` runs it."""
    model = casmech.load(MODELS / "four_bar.yaml")
    fmu = build(model, tmp_path, toolchain, "four_bar_driven")
    expected = reference(model)
    for kind in KINDS:
        assert_matches(simulate(fmu, kind), expected)


def test_an_arm_imported_from_a_urdf(toolchain, tmp_path):
    """arm6.urdf (revolute and prismatic joints, joint damping), posed as the README's
    player screenshot: falling under gravity. Its URDF limits are left out: the stops' stiff
    contact is stepped by casmech run's step bound, which an importer's CVODE has not."""
    yaml = tmp_path / "arm6.yaml"
    assert main(["import", str(ROOT / "tests/data/arm6.urdf"), "--position",
                 "lift=0.6", "--position", "elbow=-1", "-o", str(yaml), "--quiet"]) == 0
    document = yaml_module.safe_load(yaml.read_text())
    assert [joint.pop("limit") for joint in document["joints"] if "limit" in joint]
    yaml.write_text(yaml_module.safe_dump(document))
    model = casmech.load(yaml)
    fmu = build(model, tmp_path, toolchain, "arm6")
    expected = reference(model)
    for kind in KINDS:
        assert_matches(simulate(fmu, kind), expected)


def test_a_spinning_top(toolchain, tmp_path):
    """The heavy top: a spherical joint, whose quaternion and angular velocity are states."""
    model = casmech.load(MODELS / "heavy_top.yaml")
    fmu = build(model, tmp_path, toolchain, "heavy_top")
    expected = reference(model)
    for kind in KINDS:
        assert_matches(simulate(fmu, kind), expected)


def test_model_exchange_projects_the_drift_away_at_step_events(four_bar):
    """At a loose tolerance (1e-6) the ODE drifts off the loop by more than the FMU accepts
    (max(1e-9, 100 atol) = 1e-8) within an output interval; fmi2CompletedIntegratorStep asks
    for an event there and the projection puts the state back on the closures: the rows
    fmpy records before each event drifted, those after are closed (1e-12: the Gauss-Newton
    step tolerance)."""
    from fmpy import simulate_fmu

    options = {"fmi_type": "ModelExchange", "stop_time": 0.5, "relative_tolerance": 1e-6,
               "output_interval": 0.01, "output": ["constraint_violation"]}
    every = simulate_fmu(str(four_bar), record_events=True, **options)
    after = simulate_fmu(str(four_bar), record_events=False, **options)
    assert every["constraint_violation"].max() > 1e-8
    assert after["constraint_violation"].max() < 1e-12
