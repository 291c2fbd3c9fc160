"""Functions of time from data tables (schema/tables.py): the splines against scipy's and
against the function sampled, derivatives against finite differences, the periodic wrap, the
clamp, the exact integral against quadrature, runs driven by a table against runs driven by the
expression it sampled, and located errors for bad tables."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import quad
from scipy.interpolate import CubicSpline

import casmech
from casmech.errors import ModelError
from casmech.schema.tables import PiecewisePolynomial, integral, spline_coefficients, table_function
from tests.conftest import Table


def write_table(path, t, **columns):
    lines = ["t," + ",".join(columns)]
    lines += [",".join(format(v, ".17g") for v in row)
              for row in zip(t, *columns.values(), strict=True)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def derivatives(function):
    """f, f', f'' of a table's function as a casadi.Function of t (by AD)."""
    t = ca.SX.sym("t")
    f = function.casadi(t=t)
    first = ca.jacobian(f, t)
    return ca.Function("f", [t], [f, first, ca.jacobian(first, t)])


def values(function, times):
    """(len(times), 3): f, f', f'' at the times."""
    times = np.atleast_1d(np.asarray(times, float))
    mapped = derivatives(function).map(len(times))(times.reshape(1, -1))
    return np.vstack([np.asarray(v).ravel() for v in mapped]).T


# ---------------------------------------------------------------------------------- splines
@pytest.mark.parametrize("periodic", [False, True], ids=["not-a-knot", "periodic"])
def test_cubic_spline_is_scipys(rng, periodic):
    t = np.sort(rng.uniform(0, 5, 15))
    y = rng.normal(size=15)
    y[-1] = y[0] if periodic else y[-1]
    reference = CubicSpline(t, y, bc_type="periodic" if periodic else "not-a-knot")
    pp = PiecewisePolynomial(t, spline_coefficients(t, y, "cubic", periodic), periodic)
    x = ca.SX.sym("x")
    f = ca.Function("f", [x], [pp.casadi(x)])
    inside = rng.uniform(t[0], t[-1], 50)
    # an independent implementation of the same spline: rounding only (measured 1.4e-14)
    np.testing.assert_allclose([float(f(s)) for s in inside], reference(inside), rtol=1e-11,
                               atol=1e-11)


@pytest.mark.parametrize("interpolation, samples, bound", [
    ("cubic", 41, 1e-5), ("linear", 41, 4e-3), ("cubic", 161, 2e-8),
])
def test_spline_through_samples_reproduces_the_function(tmp_path, interpolation, samples, bound):
    t = np.linspace(0, 2 * np.pi, samples)
    path = write_table(tmp_path / "sin.csv", t, y=np.sin(t))
    fine = np.linspace(0, 2 * np.pi, 4001)
    error = np.max(np.abs(values(table_function(path, "y", interpolation), fine)[:, 0]
                          - np.sin(fine)))
    # measured max |table - sin| on 4001 points: cubic 41 rows 2.8e-6 (5 h^4 / 384 = 7.9e-6 is
    # the classic bound), linear 41 rows 3.1e-3 (h^2 / 8 = 3.1e-3), cubic 161 rows 6.2e-9
    assert error < bound


def test_cubic_table_of_a_cubic_is_exact(tmp_path):
    t = np.array([0.0, 0.3, 1.1, 1.5, 2.6, 3.0])
    cubic = 1 - 2 * t + 0.5 * t**2 - 0.25 * t**3
    function = table_function(write_table(tmp_path / "c.csv", t, y=cubic), "y")
    fine = np.linspace(0, 3, 301)
    got = values(function, fine)
    # not-a-knot reproduces cubics: rounding only (measured 9e-16)
    np.testing.assert_allclose(got[:, 0], 1 - 2 * fine + 0.5 * fine**2 - 0.25 * fine**3,
                               rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(got[:, 2], 1 - 1.5 * fine, rtol=1e-11, atol=1e-11)


@pytest.mark.parametrize("interpolation, periodic", [("cubic", False), ("cubic", True),
                                                     ("linear", False)])
def test_derivatives_match_finite_differences(tmp_path, rng, interpolation, periodic):
    t = np.linspace(-1, 2, 13)
    y = np.cos(2 * np.pi * t / 3) + 0.3 * np.sin(4 * np.pi * t / 3)
    y[-1] = y[0]
    function = table_function(write_table(tmp_path / "p.csv", t, y=y), "y", interpolation,
                              periodic)
    h = 1e-5
    times = rng.uniform(-4, 5, 12) if periodic else rng.uniform(-0.9, 1.9, 12)
    times = [s for s in times if interpolation == "cubic" or np.min(np.abs(t - s)) > 2 * h]
    at = values(function, times)  # f, f', f'' by AD
    below, above = values(function, np.subtract(times, h)), values(function, np.add(times, h))
    # central differences, h = 1e-5: truncation h^2 f''' / 6 ~ 1e-9, rounding 1e-11;
    # measured 2e-10 (f') and 4e-9 (f'')
    np.testing.assert_allclose(at[:, 1], (above[:, 0] - below[:, 0]) / (2 * h), rtol=1e-7,
                               atol=1e-7)
    np.testing.assert_allclose(at[:, 2], (above[:, 1] - below[:, 1]) / (2 * h), rtol=1e-6,
                               atol=1e-6)


def test_periodic_table_repeats_and_is_c2_across_the_wrap(tmp_path):
    t = np.linspace(0.5, 2.5, 21)  # period 2
    y = np.sin(np.pi * (t - 0.5)) ** 2
    function = table_function(write_table(tmp_path / "p.csv", t, y=y), "y", "cubic", True)
    base = np.linspace(0.5, 2.5, 17)
    for k in (-3, -1, 1, 4):
        # f(t + k P) = f(t): floor arithmetic only (measured 0)
        np.testing.assert_allclose(values(function, base + 2 * k), values(function, base),
                                   rtol=1e-9, atol=1e-9)
    left, right = values(function, [2.5 - 1e-9, 2.5 + 1e-9])
    # value, slope and curvature continuous at the wrap (periodic end conditions): measured
    # 4e-8 across +-1e-9 s
    np.testing.assert_allclose(left, right, rtol=1e-7, atol=1e-7)


def test_outside_the_table_the_value_is_clamped(tmp_path):
    t = np.linspace(1, 2, 6)
    function = table_function(write_table(tmp_path / "c.csv", t, y=t**2), "y", "cubic")
    got = values(function, [0.0, 0.5, 2.5, 9.0])
    # the end samples, with zero derivatives: exact (the clamp is a min/max)
    np.testing.assert_allclose(got, [[1, 0, 0], [1, 0, 0], [4, 0, 0], [4, 0, 0]], rtol=0,
                               atol=1e-14)


@pytest.mark.parametrize("periodic", [False, True], ids=["clamped", "periodic"])
def test_integral_of_a_table_matches_quadrature(tmp_path, rng, periodic):
    t = np.linspace(0.2, 1.7, 11)
    y = 2 + np.sin(2 * np.pi * (t - 0.2) / 1.5)
    function = table_function(write_table(tmp_path / "s.csv", t, y=y), "y", "cubic", periodic)
    angle = integral(function, 0.0)
    for s in rng.uniform(-1, 6, 6):
        breaks = [b + k * 1.5 for b in t for k in range(-2, 5)] if periodic else list(t)
        inside = [b for b in breaks if min(0, s) < b < max(0, s)]
        expected = quad(lambda x: function.value(t=x), 0.0, s, points=inside or None, limit=500,
                        epsabs=1e-12, epsrel=1e-12)[0]
        # exact piecewise quartic vs adaptive quadrature of the cubic: measured 3.6e-15
        np.testing.assert_allclose(angle.value(t=s), expected, rtol=1e-10, atol=1e-10)


# ------------------------------------------------------------------------------------- runs
PENDULUM = """
casmech: 1
name: table_pendulum
parameters: {{m: 5.0, L: 2.0}}
bodies:
  - {{name: bar, mass: m, inertia: [m*L**2/12, m*L**2/12, 0.01], position: [0, 0, -L/2]}}
joints:
  - {{name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [1, 0, 0],
     {motion}}}
analysis: {{type: kinematics, t_end: 3, output_step: 0.05}}
"""
DRIVEN = "pi/4 * cos(2*t)"


def run_file(path) -> Table:
    functions = casmech.compile(casmech.load(path))
    return Table(*casmech.results_table(functions, casmech.analyze(functions)))


def test_run_driven_by_a_table_equals_run_driven_by_its_expression(tmp_path):
    t = np.linspace(0, np.pi, 121)  # one period of cos(2t)
    write_table(tmp_path / "theta.csv", t, theta=np.pi / 4 * np.cos(2 * t))
    by_table = tmp_path / "table.yaml"
    by_table.write_text(PENDULUM.format(motion="driver: {angle: {table: theta.csv, column: theta, "
                                               "periodic: true}}"), encoding="utf-8")
    by_expression = tmp_path / "expression.yaml"
    by_expression.write_text(PENDULUM.format(motion=f'driver: {{angle: "{DRIVEN}"}}'),
                             encoding="utf-8")
    a, b = run_file(by_table), run_file(by_expression)
    # the table's own error (periodic cubic, h = pi/120), measured on 3001 points: value 1.5e-8
    # rad, second derivative 7.2e-4 rad/s^2 (of 3.1). Positions follow the value (L/2 = 1 m:
    # 1.5e-8 m), accelerations and reactions the second derivative: J_O 7.2e-4 = 4.8e-3 N m,
    # m L/2 7.2e-4 = 3.6e-3 N. Measured between the runs: 1.1e-8 m, 7.2e-4 rad/s^2,
    # 4.8e-3 N m, 2.5e-3 N
    for column, bound in (("bar.y", 3e-8), ("bar.z", 3e-8), ("bar.e1", 3e-8),
                          ("bar.alphax", 1.5e-3), ("pivot.tx", 1e-2), ("pivot.fy", 1e-2)):
        np.testing.assert_allclose(a[column], b[column], rtol=0, atol=bound)


def test_speed_motor_from_a_table_equals_its_expression(tmp_path):
    t = np.linspace(0, 3, 61)
    write_table(tmp_path / "speed.csv", t, w=1 + t**2 / 3)
    path = tmp_path / "speed.yaml"
    path.write_text(PENDULUM.format(motion="motor: {speed: {table: speed.csv, column: w}}"),
                    encoding="utf-8")
    table = run_file(path)
    time = table["t"]
    theta = np.unwrap(np.arctan2(table["bar.y"], -table["bar.z"]))  # from the hanging pose
    # not-a-knot reproduces the quadratic speed, and its integral is exact: measured 9e-16 rad,
    # 2.7e-15 rad/s
    np.testing.assert_allclose(theta, time + time**3 / 9, rtol=0, atol=1e-10)
    np.testing.assert_allclose(table["bar.wx"], 1 + time**2 / 3, rtol=0, atol=1e-10)


def test_basic_constraint_f_from_a_table(tmp_path):
    t = np.linspace(0, 2, 9)
    write_table(tmp_path / "gap.csv", t, gap=0.5 + 0.1 * t)
    path = tmp_path / "gap.yaml"
    path.write_text("""
casmech: 1
name: gap
bodies: [{name: block, mass: 1, inertia: [1, 1, 1], position: [0, 0, 0]}]
joints:
  - {name: slide, type: translational, body_i: ground, body_j: block, at: [0, 0, 0],
     axis: [1, 0, 0]}
  - {name: gap, type: cd, c: [1, 0, 0], body_i: ground, s_i: [0, 0, 0], body_j: block,
     s_j: [0, 0, 0], f: {table: gap.csv, column: gap, interpolation: linear}}
analysis: {type: kinematics, t_end: 1.5, output_step: 0.25}
""", encoding="utf-8")
    table = run_file(path)
    # x = f(t) with the broken line through samples of a line: exact (measured 1e-16)
    np.testing.assert_allclose(table["block.x"], 0.5 + 0.1 * table["t"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(table["block.vx"], 0.1, rtol=0, atol=1e-12)


# ----------------------------------------------------------------------------------- errors
BAD = """
casmech: 1
name: bad
bodies: [{{name: bar, mass: 1, inertia: [1, 1, 1], position: [0, 0, -1]}}]
joints:
  - name: pivot
    type: revolute
    body_i: ground
    body_j: bar
    at: [0, 0, 0]
    axis: [1, 0, 0]
    driver:
      angle: {{table: {file}, column: {column}{extra}}}
"""
ROWS = "t,a\n0,0\n1,1\n2,0\n3,1\n"


@pytest.mark.parametrize("csv, file, column, extra, code, words", [
    (ROWS, "missing.csv", "a", "", "E300", "not found"),
    (ROWS, "p.csv", "b", "", "E300", "no column 'b'"),
    ("time,a\n0,0\n1,1\n2,0\n3,1\n", "p.csv", "a", "", "E300", "no column 't'"),
    ("t,a\n0,0\n1,1\n1,0\n3,1\n", "p.csv", "a", "", "E103", "strictly increasing"),
    ("t,a\n0,0\n1,1\n2,0\n", "p.csv", "a", "", "E103", "at least 4 rows"),
    (ROWS, "p.csv", "a", ", periodic: true", "E103", "must end where it starts"),
    ("t,a\n0,0\n1,x\n2,0\n3,1\n", "p.csv", "a", "", "E103", "not a row of numbers"),
], ids=["file", "column", "no-t", "monotonic", "rows", "periodic", "number"])
def test_bad_tables_are_located_errors(tmp_path, csv, file, column, extra, code, words):
    (tmp_path / "p.csv").write_text(csv, encoding="utf-8")
    path = tmp_path / "bad.yaml"
    path.write_text(BAD.format(file=file, column=column, extra=extra), encoding="utf-8")
    with pytest.raises(ModelError) as error:
        casmech.load(path)
    found = error.value.diagnostics
    assert [d.code for d in found] == [code] and words in found[0].message
    assert found[0].source.file == str(path) and found[0].source.line == 13  # `angle:` line


def test_column_hint_names_the_close_column(tmp_path):
    (tmp_path / "p.csv").write_text("t,angle\n0,0\n1,1\n2,0\n3,1\n", encoding="utf-8")
    path = tmp_path / "bad.yaml"
    path.write_text(BAD.format(file="p.csv", column="angel", extra=""), encoding="utf-8")
    with pytest.raises(ModelError) as error:
        casmech.load(path)
    assert "angle" in error.value.diagnostics[0].hint
