"""The C library takes its DAE residuals from the registered formulations (formulations.protocol:
`residual` for each of `library_stabilizations`), not from a list of names: a formulation
registered with stabilizations to compile appears in both libraries' residuals (the mapped
one's, formulations.residuals.oracles, and the parametric one's, backends.parametric.bundle),
and what they hold is its residual with the Jacobian blocks IDAS takes, checked against the
formulation's own residual and against central differences of it."""

from dataclasses import dataclass

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.backends import cache, parametric
from casmech.backends.build import Toolchain
from casmech.equations.functions import build_functions
from casmech.formulations import residuals
from casmech.formulations.registry import FORMULATIONS
from casmech.model.lower import lower
from casmech.model.parametric import data_size, with_data
from casmech.numerics import kkt
from casmech.runtime.assembly import initial_state
from tests.conftest import MODELS
from tests.unit.formulations.test_protocol import Baumgarte

BUILT_IN = {"dae_ggl_rp", "dae_rp", "dae_ggl_romega", "dae_romega"}


@dataclass(frozen=True)
class CompiledBaumgarte(Baumgarte):
    """The toy formulation of test_protocol, asking the library for its residual; over a
    parametric bundle (functions with the model data d their last input) the residual takes d
    as its p, as formulations.protocol asks."""

    def library_stabilizations(self):
        return ("ggl",)

    def residual(self, functions, stabilization="ggl"):
        n = functions.n_coordinates
        t, x = ca.MX.sym("t"), ca.MX.sym("x", 2 * n)
        z, p = ca.MX.sym("z", 0), ca.MX.sym("p", data_size(functions.functions))
        bound = with_data(functions.functions, p)
        q, v = x[:n], x[n:]
        mass, jacobian = bound["mass_matrix"](q), bound["phi_q"](t, q)
        phi_dot = jacobian @ v - bound["nu"](t, q)
        gamma = (bound["gamma"](t, q, v) - 2 * self.a * phi_dot
                 - self.b ** 2 * bound["phi"](t, q))
        saddle = kkt.saddle(mass.sparsity(), jacobian.sparsity())
        q_ddot, _ = saddle(mass, jacobian, bound["generalized_forces"](t, q, v), gamma,
                           ca.MX(jacobian.size1(), 1))
        return ca.Function("baumgarte", [t, x, z, p], [ca.vertcat(v, q_ddot), ca.MX(0, 1)],
                           ["t", "x", "z", "p"], ["ode", "alg"])


@pytest.fixture
def compiled_baumgarte():
    FORMULATIONS.register(CompiledBaumgarte("baumgarte"))
    yield FORMULATIONS["baumgarte"]
    FORMULATIONS.unregister("baumgarte")


@pytest.fixture(scope="module")
def ir():
    return lower(casmech.load(MODELS / "double_pendulum.yaml"))


def test_the_built_in_formulations_give_the_library_its_residuals(ir):
    assert set(residuals.oracles(ir)) == BUILT_IN
    assert set(parametric.bundle(ir, dae=True)[1]) == BUILT_IN
    assert parametric.bundle(ir, dae=False)[1] == {}


def test_a_registered_formulation_is_compiled_with_its_jacobian(ir, compiled_baumgarte):
    oracles = residuals.oracles(ir)
    assert set(oracles) == BUILT_IN | {"baumgarte"}
    assert set(parametric.bundle(ir, dae=True)[1]) == BUILT_IN | {"baumgarte"}
    functions = build_functions(ir)
    own = compiled_baumgarte.system(functions).residual  # test_protocol's, run by analyze
    compiled = oracles["baumgarte"]
    q, q_dot = initial_state(functions, 0.0)  # the assembled start: a consistent state
    rng = np.random.default_rng(3)
    t, x = 0.3, np.concatenate([q, q_dot + rng.normal(scale=0.5, size=q.size)])
    z, p, u = np.zeros(0), np.zeros(0), np.zeros(0)

    def ode(at):
        return np.array(compiled["daeF"](t, at, z, p, u)[0]).ravel()

    # the same expression graph evaluated twice: equal to rounding
    np.testing.assert_allclose(ode(x), np.array(own(t, x, z, p)[0]).ravel(), rtol=1e-12,
                               atol=1e-12)
    jac = np.array(compiled["jacF"](t, x, z, p, u)[0])  # d ode / d x
    h = 1e-4
    columns = [(8 * (ode(x + h * e) - ode(x - h * e)) - (ode(x + 2 * h * e) - ode(x - 2 * h * e)))
               / (12 * h) for e in np.eye(x.size)]
    # fourth-order central differences at h = 1e-4: truncation ~h^4 = 1e-16 times the
    # residual's fifth derivative, rounding ~1e-16 * |ode| / h = 1e-11
    np.testing.assert_allclose(jac, np.array(columns).T, rtol=1e-7, atol=1e-8)


def test_registering_a_compiled_formulation_changes_the_cache_keys(ir):
    """A library cached before the registration lacks the residual: the keys of libraries
    with DAE residuals change, those without keep theirs."""
    model = casmech.load(MODELS / "double_pendulum.yaml")
    toolchain, signature = Toolchain(), "structure"

    def keys():
        return ([cache.key("model", "gcc", ("-O1",), dae) for dae in (True, False)]
                + [parametric.key(model, signature, toolchain, dae) for dae in (True, False)])

    before = keys()
    FORMULATIONS.register(CompiledBaumgarte("baumgarte"))
    try:
        during = keys()
    finally:
        FORMULATIONS.unregister("baumgarte")
    assert during[0] != before[0] and during[2] != before[2]
    assert during[1] == before[1] and during[3] == before[3]
    assert keys() == before
