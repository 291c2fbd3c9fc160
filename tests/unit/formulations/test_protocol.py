"""The Formulation protocol (formulations.protocol): a formulation added by registering one
small class runs through casmech.analyze like the built-in ones.

The toy is the body-coordinate ODE with Baumgarte stabilization, x = [q, q_dot] (r-p), its
accelerations from the saddle (KKT) system of the existing bundle's M, Phi_q, F and
gamma - 2 a Phi_dot - b^2 Phi. It is checked against rp (a second formulation of the same
motion), and its constraint drift against Phi evaluated at its rows. The built-in formulations
implement the whole protocol too: run by the generic driver they agree with their own runs.
"""

import signal
from dataclasses import dataclass

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.core.options import DynamicsOptions
from casmech.errors import Interrupted, UsageError
from casmech.formulations.protocol import Formulation, Start, States, System, indexed
from casmech.formulations.registry import FORMULATIONS
from casmech.numerics import kkt
from casmech.runtime import formulation_run
from casmech.runtime.cancel import CancelToken
from tests.conftest import MODELS

RTOL, ATOL = 1e-10, 1e-12  # both runs integrate to these


@dataclass(frozen=True)
class Baumgarte(Formulation):
    """r-p coordinates and velocities as an ODE; the constraint rows enter only through the
    accelerations, whose drift the terms 2 a Phi_dot + b^2 Phi damp."""

    a: float = 10.0
    b: float = 10.0

    def states(self, functions, stabilization="ggl"):
        n = functions.n_coordinates
        return States(indexed("q", n) + indexed("q_dot", n))

    def system(self, functions, stabilization="ggl"):
        n = functions.n_coordinates
        t, x = ca.MX.sym("t"), ca.MX.sym("x", 2 * n)
        z, p = ca.MX.sym("z", 0), ca.MX.sym("p", 0)
        q, v = x[:n], x[n:]
        mass, jacobian = functions["mass_matrix"](q), functions["phi_q"](t, q)
        phi_dot = jacobian @ v - functions["nu"](t, q)
        gamma = (functions["gamma"](t, q, v) - 2 * self.a * phi_dot
                 - self.b ** 2 * functions["phi"](t, q))
        saddle = kkt.saddle(mass.sparsity(), jacobian.sparsity())
        m = jacobian.size1()
        q_ddot, lam = saddle(mass, jacobian, functions["generalized_forces"](t, q, v), gamma,
                             ca.MX(m, 1))
        residual = ca.Function("baumgarte", [t, x, z, p], [ca.vertcat(v, q_ddot), ca.MX(0, 1)],
                               ["t", "x", "z", "p"], ["ode", "alg"])
        rows = ca.Function("rows_baumgarte", [t, x, z, p], [q, v, q_ddot, lam],
                           ["t", "x", "z", "p"], ["q", "q_dot", "q_ddot", "lam"])
        return System(residual, rows)

    def start(self, functions, system, t0, q, q_dot):
        return Start(np.concatenate([q, q_dot]), np.zeros(0), np.zeros(0))


@pytest.fixture
def baumgarte():
    FORMULATIONS.register(Baumgarte("baumgarte"))
    yield FORMULATIONS["baumgarte"]
    FORMULATIONS.unregister("baumgarte")


@pytest.fixture(scope="module")
def pendulums():
    return {name: casmech.compile(casmech.load(MODELS / f"{name}.yaml"), "interpreted")
            for name in ("pendulum", "double_pendulum")}


def drift(functions, result) -> np.ndarray:
    """max |Phi| at each of the run's rows."""
    return np.array([np.max(np.abs(functions.vector("phi", t, q)))
                     for t, q in zip(result.times, np.asarray(result.q), strict=True)])


@pytest.mark.parametrize("model", ["pendulum", "double_pendulum"])
def test_baumgarte_matches_rp(baumgarte, pendulums, model):
    functions = pendulums[model]
    toy = casmech.analyze(functions, "dynamics", t_end=1.0, output_step=0.01, rtol=RTOL,
                          atol=ATOL, formulation="baumgarte")
    rp = casmech.analyze(functions, "dynamics", t_end=1.0, output_step=0.01, rtol=RTOL,
                         atol=ATOL, formulation="rp")
    assert (toy.metadata["formulation"], toy.metadata["integrator"]) == ("baumgarte", "cvodes")
    assert np.asarray(toy.q).shape == np.asarray(rp.q).shape
    for column in ("q", "q_dot", "q_ddot"):
        reference = np.asarray(getattr(rp, column))
        # the same motion, two formulations each integrated to 1e-10: over 1 s the double
        # pendulum's differences grow to ~1e-7 of each column's scale (1 m, 10 m/s, 50 m/s^2)
        np.testing.assert_allclose(getattr(toy, column), reference, rtol=0,
                                   atol=1e-6 * max(1.0, np.max(np.abs(reference))))
    # reactions in N (about 10 to 100 here): the same to the integration error
    np.testing.assert_allclose(toy.lam, rp.lam, rtol=0, atol=1e-4)
    # the results table reads the toy's rows as it reads rp's
    names, table = casmech.results_table(functions, toy)
    assert list(names) == list(casmech.results_table(functions, rp)[0])
    assert np.all(np.isfinite(table))


def test_baumgarte_drift_is_bounded(pendulums):
    """Stabilized, the constraints hold to the integration error over the whole run; without
    the terms (a = b = 0) the same ODE drifts away from them."""
    functions = pendulums["double_pendulum"]
    drifts = {}
    for name, gains in (("damped", 10.0), ("plain", 0.0)):
        FORMULATIONS.register(Baumgarte(name, a=gains, b=gains))
        try:
            result = casmech.analyze(functions, "dynamics", t_end=10.0, output_step=0.01,
                                     rtol=1e-6, atol=1e-8, formulation=name)
        finally:
            FORMULATIONS.unregister(name)
        drifts[name] = drift(functions, result)
    damped, plain = drifts["damped"], drifts["plain"]
    # rtol 1e-6 on O(1) m positions: the damped drift stays at that size all along
    # (measured at most 5e-6), the plain one grows to 1e-4 by t = 10 s
    assert np.max(damped) < 1e-5
    assert np.max(damped[500:]) < 5 * max(np.max(damped[:500]), 1e-6)
    assert np.max(plain[800:]) > 10 * np.max(damped)


def test_registry_gives_the_option_its_choices(baumgarte, pendulums):
    functions = pendulums["pendulum"]
    assert list(FORMULATIONS)[:3] == ["rp", "romega", "joint"]
    with pytest.raises(UsageError) as error:
        casmech.analyze(functions, "dynamics", formulation="baumgart")
    assert str(error.value) == ("formulation 'baumgart' is not one of rp, romega, joint, "
                                "baumgarte, auto")
    result = casmech.analyze(functions, "dynamics", t_end=0.1, output_step=0.05,
                             options={"formulation": "baumgarte"})
    assert result.metadata["formulation"] == "baumgarte"


def test_the_registry_takes_formulations_only():
    with pytest.raises(UsageError, match="'auto' names the choice"):
        FORMULATIONS.register(Baumgarte("auto"))
    with pytest.raises(UsageError, match="not a str"):
        FORMULATIONS.register("baumgarte")
    assert list(FORMULATIONS) == ["rp", "romega", "joint"]


def test_unregistered_is_gone(pendulums):
    FORMULATIONS.register(Baumgarte("baumgarte"))
    FORMULATIONS.unregister("baumgarte")
    with pytest.raises(UsageError, match="not one of rp, romega, joint, auto$"):
        casmech.analyze(pendulums["pendulum"], "dynamics", formulation="baumgarte")
    with pytest.raises(UsageError, match="formulation"):
        casmech.analyze(pendulums["pendulum"], "dynamics",
                        options={"formulation": "baumgarte"})


def test_a_registered_formulation_is_cancelled_with_its_rows(baumgarte, pendulums):
    """The generic driver polls the run's token between its solver calls (chunk: 100 output
    intervals when rows are wanted as they come) and keeps the rows computed."""
    token = CancelToken()
    with pytest.raises(Interrupted) as caught:
        casmech.analyze(pendulums["double_pendulum"], "dynamics", t_end=1.0,
                        output_step=0.001, formulation="baumgarte", token=token,
                        progress=lambda t: t >= 0.05 and token.cancel(signal.SIGTERM),
                        options={"chunk": 100})
    assert caught.value.signum == signal.SIGTERM
    assert 50 <= len(caught.value.partial) <= 101


def pendulum_file(tmp_path, formulation: str):
    """models/pendulum.yaml with `formulation:` in its analysis block: (path, that line)."""
    lines = (MODELS / "pendulum.yaml").read_text().splitlines()
    line = lines.index("  type: dynamics") + 1  # 0-based: the line after it
    lines.insert(line, f"  formulation: {formulation}")
    path = tmp_path / f"pendulum_{formulation}.yaml"
    path.write_text("\n".join(lines) + "\n")
    return path, line + 1


def test_unknown_formulation_in_a_file_is_located(tmp_path):
    path, line = pendulum_file(tmp_path, "baumgart")
    with pytest.raises(casmech.ModelError) as error:
        casmech.load(path)
    message = str(error.value)
    assert f"{path}:{line}:16: error[E103] analysis.formulation" in message
    assert "expected: rp | romega | joint | auto" in message


def test_a_registered_formulation_in_a_file(tmp_path, baumgarte):
    """The file's `formulation:` takes a registered formulation, and a misspelt one is a
    located error listing it."""
    path, _ = pendulum_file(tmp_path, "baumgarte")
    result = casmech.analyze(casmech.compile(casmech.load(path)))
    assert result.metadata["formulation"] == "baumgarte"
    path, line = pendulum_file(tmp_path, "baumgart")
    with pytest.raises(casmech.ModelError) as error:
        casmech.load(path)
    message = str(error.value)
    assert f"{path}:{line}:16: error[E103] analysis.formulation" in message
    assert "expected: rp | romega | joint | baumgarte | auto" in message
    assert "did you mean 'baumgarte'?" in message


@pytest.mark.parametrize("name", ["rp", "romega"])
def test_builtins_through_the_protocol_on_a_compiled_bundle(name, quick_builds):
    """The generic driver on a compiled parametric bundle, whose DAE residuals have IDAS's
    signature (t, x, z, p, u) and take the model data after p: the own run's motion."""
    from casmech.backends import codegen

    if not codegen.available():
        pytest.skip("no C compiler")
    functions = casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"), "compiled")
    assert functions.data is not None  # the parametric library
    asked = formulation_run.Run(0.0, 0.5, 0.01, RTOL, ATOL, DynamicsOptions(formulation=name))
    own = formulation_run.run(functions, name, asked)
    generic = formulation_run.generic(functions, FORMULATIONS[name], asked)
    for column in ("q", "q_dot"):
        reference = np.asarray(getattr(own, column))
        # the same equations from the same start at rtol 1e-10 (IDAS with the library's
        # Jacobian against IDAS with CasADi's of the same residual): ~1e-7 of the scale
        np.testing.assert_allclose(getattr(generic, column), reference, rtol=0,
                                   atol=1e-6 * max(1.0, np.max(np.abs(reference))))


@pytest.mark.parametrize("name", ["rp", "romega", "joint"])
@pytest.mark.parametrize("model", ["double_pendulum", "four_bar"])
def test_builtins_through_the_protocol(name, model, pendulums):
    """Each built-in formulation's System and Start, integrated by the generic driver, give
    its own run's motion (both at rtol 1e-10)."""
    functions = pendulums.get(model) or casmech.compile(casmech.load(MODELS / f"{model}.yaml"),
                                                        "interpreted")
    asked = formulation_run.Run(0.0, 1.0, 0.01, RTOL, ATOL,
                                DynamicsOptions(formulation=name))
    own = formulation_run.run(functions, name, asked)
    generic = formulation_run.generic(functions, FORMULATIONS[name], asked)
    states = FORMULATIONS[name].states(functions)
    system = FORMULATIONS[name].system(functions)
    assert len(states.differential) == system.residual.size1_in(1)
    assert len(states.algebraic) == system.n_z
    assert generic.metadata["formulation"] == name
    for column in ("q", "q_dot", "q_ddot"):
        reference = np.asarray(getattr(own, column))
        # the same equations from the same start at rtol 1e-10 (the joint run's own method
        # is Adams, the generic CVODES's BDF; no projections): ~1e-7 of each column's scale
        np.testing.assert_allclose(getattr(generic, column), reference, rtol=0,
                                   atol=1e-6 * max(1.0, np.max(np.abs(reference))))
