"""casmech.core.traced_steps: a traced step's expansion equals the step run on its arguments
(traced_steps.direct), whatever form its constant arguments take (casadi.DM, dense or with
structural zeros, a NumPy array, a number), and a step is traced again for an argument of
another sparsity, not projected onto the first one's."""

import casadi as ca
import numpy as np

from casmech.core import traced_steps


@traced_steps.traced
def _step(x, matrix, vector, scale):
    """A step mixing its symbolic argument with constants of several forms."""
    return matrix @ x + scale * vector, ca.cross(x, vector)


def _values(expressions, x, at) -> list[np.ndarray]:
    function = ca.Function("f", [x], list(expressions))
    return [np.array(v) for v in function(at)] if function.n_out() > 1 else [np.array(function(at))]


def test_constants_of_every_form_expand_as_the_step_run_directly(rng):
    x = ca.SX.sym("x", 3)
    at = rng.normal(size=3)
    sparse = ca.DM(ca.Sparsity.diag(3), rng.normal(size=3))  # structural zeros off the diagonal
    forms = [(ca.DM(rng.normal(size=(3, 3))), ca.DM(rng.normal(size=3)), 2.5),
             (sparse, rng.normal(size=3), ca.DM(0.5)),
             (np.eye(3), np.array([1.0, -2.0, 0.25]), 3)]
    for matrix, vector, scale in forms:
        traced = _step(x, matrix, vector, scale)
        with traced_steps.direct():
            direct = _step(x, ca.SX(ca.DM(matrix)), ca.SX(ca.DM(vector)), scale)
        for a, b in zip(_values(traced, x, at), _values(direct, x, at), strict=True):
            # the same SX operations up to the association of constant products: round-off
            np.testing.assert_allclose(a, b, rtol=1e-14, atol=1e-14)


def test_another_sparsity_is_traced_again(rng):
    x = ca.SX.sym("x", 3)
    diagonal = ca.DM(ca.Sparsity.diag(3), [1.0, 2.0, 3.0])
    full = ca.DM(rng.normal(size=(3, 3)))
    vector = ca.DM([0.0, 1.0, 0.0])
    first = _step(x, diagonal, vector, 1.0)[0]
    second = _step(x, full, vector, 1.0)[0]
    at = rng.normal(size=3)
    # each expansion is its own matrix's product (the full matrix not projected on a diagonal)
    np.testing.assert_allclose(_values([first], x, at)[0].ravel(),
                               np.diag([1.0, 2.0, 3.0]) @ at + [0, 1, 0], rtol=1e-14, atol=0)
    np.testing.assert_allclose(_values([second], x, at)[0].ravel(),
                               np.array(full) @ at + [0, 1, 0], rtol=1e-14, atol=1e-15)
