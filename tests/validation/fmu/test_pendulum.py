"""An FMU of the double pendulum (a tree: the joint-coordinate ODE): valid, self-contained,
and simulated by fmpy (Model Exchange on its CVODE, Co-Simulation on the FMU's integrator) as
`casmech run` runs the model, at its own parameters and at others set through fmpy."""

import shutil
import subprocess
import zipfile

import numpy as np
import pytest

import casmech
from tests.helpers.fmu import MODELS, assert_matches, build, reference, simulate
from tests.helpers.fmu import slave as instance

KINDS = ("ModelExchange", "CoSimulation")
CHANGED = {"L1": 1.3, "m2": 2.0, "theta2": 0.3}  # two fixed (the start pose), one tunable


@pytest.fixture(scope="module")
def fmu(toolchain, tmp_path_factory):
    model = casmech.load(MODELS / "double_pendulum.yaml")
    return build(model, tmp_path_factory.mktemp("fmu"), toolchain, "double_pendulum")


@pytest.fixture(scope="module")
def expected():
    return reference(casmech.load(MODELS / "double_pendulum.yaml"))


def test_fmpy_validates_it(fmu):
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(fmu)) == []


def test_the_archive_holds_the_binary_the_description_and_the_sources(fmu):
    from fmpy import read_model_description

    names = set(zipfile.ZipFile(fmu).namelist())
    assert {"modelDescription.xml", "binaries/linux64/double_pendulum.so",
            "sources/casmech_fmu.c"} <= names
    description = read_model_description(str(fmu))
    assert description.modelExchange.modelIdentifier == "double_pendulum"
    assert description.coSimulation.modelIdentifier == "double_pendulum"
    states = [v.name for v in description.modelVariables if v.derivative is not None]
    assert states == ["der(pivot.angle)", "der(elbow.angle)", "der(pivot.angle_dot)",
                      "der(elbow.angle_dot)"]
    kinds = {v.name: v.variability for v in description.modelVariables
             if v.causality == "parameter"}
    assert kinds == {"L1": "fixed", "L2": "fixed", "theta1": "fixed", "theta2": "fixed",
                     "m1": "tunable", "m2": "tunable", "w": "tunable"}


def test_the_binary_needs_no_python(fmu, tmp_path):
    """Self-contained: the shared library links the C library and libm, nothing else."""
    readelf = shutil.which("readelf")
    if readelf is None:
        pytest.skip("no readelf")
    zipfile.ZipFile(fmu).extractall(tmp_path)
    dynamic = subprocess.run([readelf, "-d", str(tmp_path / "binaries/linux64/double_pendulum.so")],
                             capture_output=True, text=True, check=True).stdout
    needed = {line.split("[")[1].split("]")[0] for line in dynamic.splitlines()
              if "(NEEDED)" in line}
    assert needed <= {"libm.so.6", "libc.so.6"}
    symbols = subprocess.run(["nm", "-D", "--defined-only",
                              str(tmp_path / "binaries/linux64/double_pendulum.so")],
                             capture_output=True, text=True, check=True).stdout.split()
    assert "fmi2DoStep" in symbols and "fmi2GetDerivatives" in symbols
    assert not [s for s in symbols if s.startswith("cm_")]  # only the FMI functions


@pytest.mark.parametrize("kind", KINDS)
def test_it_moves_as_casmech_runs_it(fmu, expected, kind):
    assert_matches(simulate(fmu, kind), expected)


@pytest.mark.parametrize("kind", KINDS)
def test_parameters_set_through_fmpy_change_the_physics_as_set_does(fmu, kind):
    model = casmech.load(MODELS / "double_pendulum.yaml",
                         {name: str(value) for name, value in CHANGED.items()})
    expected = reference(model)
    got = simulate(fmu, kind, start_values=CHANGED)
    assert_matches(got, expected)
    default = simulate(fmu, kind)
    assert abs(default["rod2.x"] - got["rod2.x"]) > 1e-2  # the change mattered


def test_a_fixed_parameter_is_refused_after_initialization_a_tunable_one_is_not(fmu, tmp_path):
    from fmpy.fmi1 import FMICallException

    slave, refs = instance(fmu, tmp_path)
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    slave.doStep(0.0, 0.1)
    slave.setReal([refs["m2"]], [2.0])
    slave.doStep(0.1, 0.1)
    with pytest.raises(FMICallException):
        slave.setReal([refs["L1"]], [1.5])
    slave.terminate()
    slave.freeInstance()


def test_states_set_before_initialization_are_where_it_starts(fmu):
    """A state given by the importer replaces the file's start (a tree: taken as it is)."""
    from fmpy import simulate_fmu

    result = simulate_fmu(str(fmu), fmi_type="CoSimulation", stop_time=0.01,
                          output_interval=0.01, start_values={"pivot.angle": 0.25},
                          output=["rod1.e2", "rod1.e0"])
    angle = 2 * np.arctan2(result["rod1.e2"][0], result["rod1.e0"][0])
    # the file's theta1 = pi/2 plus the 0.25 rad given (the joint's angle from the file's pose)
    np.testing.assert_allclose(angle, np.pi / 2 + 0.25, rtol=0, atol=1e-12)  # roundoff


def test_its_sources_build_the_same_fmu(fmu, tmp_path):
    """sources/ is complete: compiled alone (here at -O0), it gives the binary's motion."""
    from fmpy import simulate_fmu

    compiler = shutil.which("gcc") or shutil.which("cc")
    if compiler is None:
        pytest.skip("no C compiler")
    zipfile.ZipFile(fmu).extractall(tmp_path)
    sources = sorted(str(p) for p in (tmp_path / "sources").glob("*.c"))
    binary = tmp_path / "binaries/linux64/double_pendulum.so"
    binary.unlink()
    subprocess.run([compiler, "-std=c99", "-fPIC", "-O0", "-shared", *sources, "-o", str(binary),
                    "-lm"], check=True, capture_output=True)
    options = {"fmi_type": "CoSimulation", "stop_time": 0.5, "relative_tolerance": 1e-10,
               "output": ["rod2.x"]}
    rebuilt = simulate_fmu(str(tmp_path), **options)
    original = simulate_fmu(str(fmu), **options)
    # the same C at another optimization level: round-off apart
    np.testing.assert_allclose(rebuilt["rod2.x"], original["rod2.x"], rtol=0, atol=1e-12)


def test_co_simulation_controls_its_error(fmu, expected):
    """The FMU's integrator meets the tolerance it is given (communication steps of 0.5 s, so
    its own steps are the tolerance's): the error at t = 1 s follows it down."""
    from fmpy import simulate_fmu

    tolerances = (1e-4, 1e-6, 1e-8)
    errors = []
    for tolerance in tolerances:
        result = simulate_fmu(str(fmu), fmi_type="CoSimulation", stop_time=1.0,
                              relative_tolerance=tolerance, output_interval=0.5,
                              output=["rod2.x"])
        errors.append(abs(result["rod2.x"][-1] - expected["rod2.x"]))
    for tolerance, error in zip(tolerances, errors, strict=True):
        assert error < 10 * tolerance  # a global error over 1 s of a chaotic motion
    assert errors[0] > 10 * errors[1] > 100 * errors[2]


def test_outputs_are_known_in_initialization_mode(fmu, tmp_path):
    """A master may read outputs before initialization ends: the start pose at the
    parameters set so far (rod 1's centre at -L1/2 sin(theta1), 0, -L1/2 cos(theta1))."""
    slave, refs = instance(fmu, tmp_path)
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    names = ["rod1.x", "rod1.z", "rod2.x"]
    before = slave.getReal([refs[n] for n in names])
    slave.setReal([refs["L1"], refs["theta1"]], [1.3, 0.4])
    during = slave.getReal([refs[n] for n in names])
    slave.exitInitializationMode()
    after = slave.getReal([refs[n] for n in names])
    slave.terminate()
    slave.freeInstance()
    # the closed form; the start is solved by Gauss-Newton to 1e-12 (its step) and round-off
    np.testing.assert_allclose(before[:2], [-0.5, 0.0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(during[:2], [-0.65 * np.sin(0.4), -0.65 * np.cos(0.4)], rtol=0,
                               atol=1e-12)
    np.testing.assert_allclose(after, during, rtol=0, atol=1e-15)  # nothing moved at t0


def test_a_tunable_parameter_changes_the_physics_from_then_on(fmu, tmp_path):
    """m2 doubled between steps at t = 0.5: the energy (no damping) is constant before and
    after, and jumps by rod 2's own energy there (it is linear in m2: its inertia is m2 times
    a length squared), computed from the FMU's outputs."""
    slave, refs = instance(fmu, tmp_path)
    slave.setupExperiment(tolerance=1e-10, startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    rod2 = ["rod2.vx", "rod2.vy", "rod2.vz", "rod2.wy", "rod2.z"]
    energy, t = [], 0.0
    for k in range(100):
        if k == 50:
            vx, vy, vz, wy, z = slave.getReal([refs[n] for n in rod2])
            # rod 2's energy per kg (L2 = 1, w = 0.04: J_yy = m2 (1 + 0.04^2) / 12)
            per_kg = 0.5 * (vx**2 + vy**2 + vz**2) + 0.5 * (1 + 0.04**2) / 12 * wy**2 + 9.81 * z
            slave.setReal([refs["m2"]], [2.0])
            jump = energy[-1] + per_kg * (2.0 - 1.0)
            energy.append(slave.getReal([refs["energy"]])[0])
            # the energy at the new mass, of the same state
            np.testing.assert_allclose(energy[-1], jump, rtol=0, atol=1e-12)  # round-off
        slave.doStep(t, 0.01)
        t += 0.01
        energy.append(slave.getReal([refs["energy"]])[0])
    slave.terminate()
    slave.freeInstance()
    before, after = np.array(energy[:50]), np.array(energy[50:])
    # no damping: conserved to the integrator's tolerance (1e-10) times the motion
    np.testing.assert_allclose(before, before[0], rtol=0, atol=1e-7)
    np.testing.assert_allclose(after, after[0], rtol=0, atol=1e-7)
    assert abs(after[0] - before[0]) > 0.1
