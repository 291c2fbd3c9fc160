"""casadi.integrator's problem for a tree's ODE under CVODES's functional iteration (Adams),
which never evaluates a Jacobian.

casadi evaluates the right-hand side through an MX function it makes of the problem it is
given. Given expressions over a call of the ODE wrapped in a Function declared not
differentiable (JointSystem.functional_problem, numerics.lazy_jacobian), every evaluation goes
through two MX functions, the integrator's and the wrapper's (each a memory checkout and an
MX evaluation around the ODE's). Given a Function of the integrator's own DAE signature,
(t, x, z, p, u) -> (ode, alg, quad, zero), declared not differentiable and calling the ODE
itself, it goes through one: the same ODE on the same states, so the same solution. Creating
an integrator of it analyses the ODE's Jacobian sparsity, in time growing faster than the
square of the states (docs/decisions/cvodes-per-step.md), so ODEs of more than
DIRECT_STATES states keep the wrapped form.
"""

from __future__ import annotations

import casadi as ca

from casmech.formulations.joint_system import JointSystem

DIRECT_STATES = 128  # the most states whose functional problem calls the ODE directly
NAMES_IN, NAMES_OUT = ("t", "x", "z", "p", "u"), ("ode", "alg", "quad", "zero")


def problem(system: JointSystem, functional: bool = True) -> dict | ca.Function:
    """The problem CVODES integrates a tree's ODE (t, x) -> ode as: with `functional`
    iteration, up to DIRECT_STATES states, a Function of the integrator's signature calling
    the ODE directly (its inputs and outputs by name), else JointSystem.functional_problem;
    with Newton iteration JointSystem.problem (with its Jacobian)."""
    if not functional:
        return system.problem
    if system.layout.n_x > DIRECT_STATES:
        return system.functional_problem
    dynamics = system.dynamics
    symbols = {name: ca.MX.sym(name, dynamics.sparsity_in(name)) for name in dynamics.name_in()}
    outputs = dynamics.call(symbols)
    empty = ca.MX(0, 1)
    return ca.Function(dynamics.name(), [symbols.get(name, empty) for name in NAMES_IN],
                       [outputs.get(name, empty) for name in NAMES_OUT], list(NAMES_IN),
                       list(NAMES_OUT), {"is_diff_in": [False] * len(NAMES_IN)})
