"""The Chrono/ADAMS decks (tests/reference/chrono_adams/adams_models) imported by casmech.

- every deck imports into YAML that casmech's own loader accepts, with the deck's comments and a
  header naming the source;
- the imported model equals the hand-written one in models/validation/ (same results to 1e-9
  over 0.5 s: the full 5 s of those models is run by
  tests/validation/runtime/test_validation_adams.py);
- the imported model's dynamics matches the ADAMS reference data over 0..2 s (201 output
  rows; kept short for speed: the hand-written models, equal to these, are held to the full
  0..5 s) within Chrono's tolerances (tests/helpers/reference_data.py, used read-only);
- the two decks that do not describe their data (README of tests/reference) are held to the
  exact solutions of their own equations instead, and RotSpring with Chrono's spring values
  (set through the imported parameters) matches the data.
"""

from dataclasses import replace

import casadi as ca
import numpy as np
import pytest

from tests.conftest import run_model
from tests.helpers.importers import DECKS, G, imported, integrate, run
from tests.helpers.reference_data import (
    ADAMS_CASES,
    MOTION,
    VALIDATION_MODELS,
    columns,
    joint_reaction,
    rms_errors,
    rotation_angle,
)

CASES = {case.name: case for case in ADAMS_CASES}
# deck case -> (body, joint) names the importer gives (adams_view_name, else part_<id>)
NAMES = {
    "Revolute_Case01": ("part_02", "joint_1"), "Spherical_Case01": ("part_02", "joint_1"),
    "Universal_Case01": ("part_02", "joint_1"), "Prismatic_Case01": ("part_02", "joint_1"),
    "Cylindrical_Case01": ("part_02", "joint_1"), "Distance_Case01": ("part_02", "gcon_1"),
    "RotSpring_Case01": ("part_2", "joint_1"),
}
# the deck's SFORCE says k = RTOD, c = 0.05 RTOD; the data were made with Chrono's (200, 10)
CHRONO_SPRING = {"torsion_spring_2_k": "200", "torsion_spring_2_c": "10"}
ALL_DECKS = sorted(DECKS.glob("*.adm"))
SPAN = 2.0  # s, of the comparison with the ADAMS data
_RUNS = {}


def dynamics(name):
    """The imported deck's functions and dynamics over 0..SPAN (cached per session)."""
    if name not in _RUNS:
        _, _, functions = imported(deck(name), overrides(name))
        _RUNS[name] = functions, run(functions, analysis="dynamics", t_end=SPAN,
                                     output_step=0.01, rtol=1e-10, atol=1e-12)
    return _RUNS[name]


def deck(name):
    return DECKS / f"test_{name.replace('TranSpring', 'TransSpring')}.adm"


def overrides(name):
    return CHRONO_SPRING if name == "RotSpring_Case01" else None


@pytest.mark.parametrize("path", ALL_DECKS, ids=lambda p: p.stem)
def test_every_deck_imports_validates_and_keeps_its_comments(path):
    text, warnings, functions = imported(path)
    assert text.startswith(f"# Imported by `casmech import` from the Adams/Solver dataset "
                           f"{path.name}")
    deck_lines = path.read_text().splitlines()
    # every '!' comment of the deck is in the YAML as a comment
    yaml_comments = {line.strip().lstrip("#").strip() for line in text.splitlines()
                     if line.strip().startswith("#")}
    comments = {line.split("!", 1)[1].strip() for line in deck_lines if "!" in line}
    assert comments <= yaml_comments, comments - yaml_comments
    # every warning names a statement's line (GRAPHICS, REQUEST, ... are not translated)
    assert warnings
    for warning in warnings:
        assert warning.severity == "warning"
        assert deck_lines[warning.source.line - 1].upper().startswith(
            warning.path.split("/")[0]), warning.format()
    assert len(functions.body_names) == 1


@pytest.mark.parametrize("name", NAMES)
def test_imported_deck_equals_hand_written_model(name):
    """Same results table (every column, same order) as models/validation/ over 0.5 s, both
    run with the same settings (so that the integrator takes the same steps)."""
    settings = dict(analysis="dynamics", t_end=0.5, output_step=0.01, rtol=1e-10, atol=1e-12)
    _, _, functions = imported(deck(name), overrides(name))
    ours = run(functions, **settings)
    _, theirs = run_model(VALIDATION_MODELS / CASES[name].model, **settings)
    assert len(ours.names) == len(theirs.names)
    # the same equations from the same numbers: identical up to roundoff in the Euler angle
    # conversion (measured: 0 difference on every case)
    np.testing.assert_allclose(ours.values, theirs.values, rtol=0, atol=1e-9)


def rotspring_reactions(functions, table, joint):
    """Chrono writes joint reaction + spring torque, both on ground (reference_data's
    rotspring_on_ground, with the imported parameter names)."""
    force, torque = joint_reaction(table, joint)
    k, c = (functions.ir.parameters[f"torsion_spring_2_{key}"] for key in "kc")
    axis = np.array([0.0, 1.0, 0.0])
    th = rotation_angle(table, "part_2", axis)
    th_dot = columns(table, "part_2", MOTION["Avel"]) @ axis
    spring = -(k * th + c * th_dot)[:, None] * axis
    return {"Rforce": -force, "Rtorque": -(torque + spring)}


@pytest.mark.parametrize("name", NAMES)
def test_imported_deck_matches_adams_data_within_chrono_tolerances(name):
    """Chrono's pass rule over 0..SPAN: per column RMS(casmech - ADAMS) <= tolerance."""
    body, joint = NAMES[name]
    case = replace(CASES[name], body=body, joint=joint)
    if name == "RotSpring_Case01":
        case = replace(case, reactions=rotspring_reactions)
    functions, table = dynamics(name)
    errors = rms_errors(case, functions, table, rows=slice(0, len(table.values)))
    failed = {q: float(np.max(e)) for q, e in errors.items() if np.max(e) > case.tolerance(q)}
    print(f"\n{name}: " + ", ".join(f"{q} {np.max(e):.1e}" for q, e in errors.items()))
    assert not failed, f"{name}: RMS above Chrono's tolerance: {failed}"


def test_rotspring_deck_values_match_exact_swing():
    """With the deck's own spring (k = RTOD N m/rad, c = 0.05 RTOD): the exact 1-DOF
    reduction 4.1 th'' = 2 g cos(th) - k th - c th' (I about the pivot 0.1 + 1 * 2^2)."""
    _, _, functions = imported(deck("RotSpring_Case01"))
    table = run(functions, analysis="dynamics", t_end=1.0, output_step=0.01, rtol=1e-10,
                atol=1e-12)
    k, c = 180 / np.pi, 0.05 * 180 / np.pi
    th = ca.SX.sym("th", 2)
    ode = ca.vertcat(th[1], (G * 2 * ca.cos(th[0]) - k * th[0] - c * th[1]) / 4.1)
    exact = integrate(th, ode, [0.0, 0.0], table["t"])[0]
    position = np.column_stack([table["part_2.x"], table["part_2.z"]])
    # model rtol 1e-10 / atol 1e-12 over 1 s: global error measured below 1e-8 m
    np.testing.assert_allclose(position, np.column_stack([2 * np.cos(exact),
                                                          -2 * np.sin(exact)]),
                               rtol=0, atol=1e-6)


def test_transspring_deck_matches_point_mass_spring_pendulum():
    """The deck: a free 1 kg body at (0, 2, 0) on a spring-damper to the origin (k = 100,
    c = 1, free length 2). The force passes through the CM, so the CM moves as a point mass:
    x'' = g - (k (l - 2) + c l') x / l, integrated by CVODES."""
    _, _, functions = imported(deck("TranSpring_Case01"))
    table = run(functions, analysis="dynamics", t_end=1.0, output_step=0.01, rtol=1e-10,
                atol=1e-12)
    x = ca.SX.sym("x", 6)
    length = ca.norm_2(x[:3])
    tension = 100 * (length - 2) + 1 * ca.dot(x[:3], x[3:]) / length
    ode = ca.vertcat(x[3:], ca.DM([0, 0, -G]) - tension * x[:3] / length)
    exact = integrate(x, ode, [0, 2, 0, 0, 0, 0], table["t"])[:3].T
    # model rtol 1e-10 / atol 1e-12 over 1 s: global error measured ~1e-9 m
    np.testing.assert_allclose(columns(table, "part_2", "xyz"), exact, rtol=0, atol=1e-6)
