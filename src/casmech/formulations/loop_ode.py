"""A joint system's loop closures as an ODE of the tree's states, and the projection of a state
back onto the loops' constraints: the projection method of Hairer, Lubich and Roche (Hairer and
Wanner II, VII.2) for an explicit Runge-Kutta method (runtime.loop_integration).

State x = [theta; u] as the joint DAE's (formulations/joint_system.py). At each (t, x) the loops'
unit-row multipliers and the accelerations come from the DAE's saddle system at acceleration
level (joint_system.saddle_terms, solved by numerics.kkt.solve_saddle with the DAE's row mask
w), so that

    ode(t, x) = [theta_dot(theta, u); u_dot],   [M P^T; P -diag(w)] [u_dot; lam] = [F; gamma]

keeps d^2/dt^2 Phi_c = 0 along the solution; the positions and velocities drift from
Phi_c = 0 and d/dt Phi_c = 0 by the integrator's error only, and `project` takes them back:

- positions: Gauss-Newton on the kept rows' S Phi_c(t, theta) = 0 (the DAE's algebraic rows at
  z = 0), each correction in velocity space du the M-weighted least-norm solution of
  P du = -S Phi_c (the same saddle solve with F = 0: [M P^T; P -diag(w)] [du; .] = [0; -S Phi]),
  taken to coordinates along theta_dot's derivative in u (theta += d theta_dot/du du: a joint's
  quaternion coordinates move along its rates). The metric M is the joint-space mass matrix at
  the state given (held over the iterations): the kinetic-energy metric, which weighs angles
  and lengths of different joints in one unit (joules per velocity squared) where the
  Euclidean one would depend on the units of theta. POSITION_ITERATIONS Gauss-Newton steps:
  the drift of an accepted step is the integrator's local error e (|e| <~ rtol of
  coordinates ~1), and each step squares it (e -> C e^2), so three take a drift up to ~1e-2
  to roundoff; a fixed count keeps the projection one branch-free graph (the iterations
  unrolled; tests/unit/formulations/test_loop_ode.py checks that two do not suffice at the
  loosest rtol).
- velocities: the same solve with the right side -S d/dt Phi_c (the DAE's second algebraic
  rows at z = 0) at the projected positions: affine in u, so one step is exact; M-weighted, it
  is the velocity an inelastic impulse along the rows gives, the kinetic energy's closest.
- entries of the projected state below FLUSH in magnitude are zero (FLUSH's comment).

Every term is read from the system's own functions (saddle_terms, the DAE's `dynamics` at
z = 0: theta_dot and the rows' residuals); CasADi differentiates theta_dot. Where the saddle
matrix is singular (a singular pose: P lost rank, no row masked) solve_saddle's SX gives NaN,
which the integrator reports as a non-finite state.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.core.records import record
from casmech.numerics.kkt import solve_saddle

# Gauss-Newton steps of the position projection (module docstring)
POSITION_ITERATIONS = 3
# a projected state's entries below this in magnitude are set to zero: a coordinate the loops
# hold at zero (a planar loop's out-of-plane angles and rates) is otherwise taken a little
# closer to zero by every projection, into subnormal numbers, whose arithmetic costs ~100
# times a normal one's in the compiled ODE; its square stays a normal number
FLUSH = 1e-150


@record
class LoopODE:
    """The loops' ODE and projection of one joint system and row mask."""

    ode: ca.Function  # (t, x) -> ode
    project: ca.Function  # (t, x) -> x on Phi_c = 0 and d/dt Phi_c = 0 (kept rows)
    n_theta: int


def _symbols(*functions: ca.Function):
    """SX when every function is SX (their graphs inlined and shared), else MX."""
    return ca.SX if all(f.is_a("SXFunction") for f in functions) else ca.MX


def build(terms: ca.Function, dynamics: ca.Function, n_theta: int, mask,
          iterations: int = POSITION_ITERATIONS) -> LoopODE:
    """The loops' ODE and projection (module docstring) from a joint system's saddle terms
    (formulations.joint_system.saddle_terms: (t, x) -> (M, P, F, gamma)) and its DAE
    (JointSystem.dynamics: (t, x, z, p) -> (ode, alg)), with the DAE's row mask (1: a row
    masked, runtime's Loops.mask) as constants of the graph; n_theta: the coordinates in x.
    One SX graph each where both functions are SX, else MX calling them. Inputs after those
    (a parametric build's model data d, the same for both) become the results' trailing
    inputs."""
    sym = _symbols(terms, dynamics)
    t, x, extra = _inputs(sym, terms)
    w = _mask(terms, mask)
    mass, jacobian, forces, gamma = terms(t, x, *extra)
    u_dot, _ = solve_saddle(mass, jacobian, forces, gamma, w)
    ode = ca.vertcat(_rates(dynamics, w, t, x, extra)[0][:n_theta], u_dot)
    return LoopODE(_function("joint_loop_ode", terms, [t, x, *extra], ode, "ode"),
                   projection(terms, dynamics, n_theta, mask, iterations), n_theta)


def consistent_ode(acceleration: ca.Function, dynamics: ca.Function, mask) -> ca.Function:
    """(t, x) -> ode: the DAE's ODE at the multipliers of its acceleration system
    (JointSystem.acceleration_system: the kept rows' constraint accelerations, affine in
    them, set to zero; the masked rows' multipliers zero, as formulations.joint_start.Loops.z
    solves them), for a system whose forces only its own functions hold (a controller's:
    runtime.projected_loops); `build`'s ODE where the saddle terms hold them, in fewer
    instructions."""
    sym = _symbols(acceleration, dynamics)
    t, x, extra = _inputs(sym, acceleration)
    matrix, base = acceleration(t, x, *extra)
    m = base.size1()
    keep = [int(k) for k in np.flatnonzero(np.asarray(mask, float) == 0)]
    lam = sym.zeros(m)
    if keep:
        lam[keep] = ca.solve(matrix[keep, keep], -base[keep])
    ode = dynamics(t, x, ca.vertcat(lam, sym.zeros(m)), ca.DM(np.asarray(mask, float)),
                   *extra)[0]
    return _function("joint_loop_ode", acceleration, [t, x, *extra], ode, "ode")


def projection(terms: ca.Function, dynamics: ca.Function, n_theta: int, mask,
               iterations: int = POSITION_ITERATIONS) -> ca.Function:
    """(t, x) -> x projected onto the kept rows (module docstring), from the saddle terms'
    M and P and the DAE's theta_dot and rows, as `build`'s (the geometry and the masses
    only: no force enters); trailing inputs as `build`'s."""
    sym = _symbols(terms, dynamics)
    n_x, m = terms.size1_in(1), terms.size1_out(1)
    w = _mask(terms, mask)
    t, x, extra = _inputs(sym, terms)
    mass = terms(t, x, *extra)[0]
    theta_dot = _rates(dynamics, w, t, x, extra)[0][:n_theta]
    # the position step as a function of (t, x): theta + d theta_dot/du du
    du = sym.sym("du", n_x - n_theta)
    along = ca.Function("along", [t, x, du, *extra], [ca.jtimes(theta_dot, x, ca.vertcat(
        sym.zeros(n_theta), du))])
    zero = sym.zeros(n_x - n_theta)
    state = x
    for _ in range(iterations):
        position = _rates(dynamics, w, t, state, extra)[1][:m]
        step, _ = solve_saddle(mass, terms(t, state, *extra)[1], zero, -position, w)
        state = ca.vertcat(state[:n_theta] + along(t, state, step, *extra), state[n_theta:])
    velocity = _rates(dynamics, w, t, state, extra)[1][m:]
    step, _ = solve_saddle(mass, terms(t, state, *extra)[1], zero, -velocity, w)
    projected = ca.vertcat(state[:n_theta], state[n_theta:] + step)
    projected = ca.if_else(ca.fabs(projected) < FLUSH, 0, projected)
    return _function("joint_loop_project", terms, [t, x, *extra], projected, "x_projected")


def _inputs(sym, function: ca.Function) -> tuple:
    """(t, x, [the inputs after them]) as symbols of `function`'s shapes."""
    t, x = sym.sym("t"), sym.sym("x", function.size1_in(1))
    return t, x, [sym.sym(function.name_in(k), function.sparsity_in(k))
                  for k in range(2, function.n_in())]


def _mask(terms: ca.Function, mask) -> ca.DM:
    return ca.DM(np.asarray(mask, float).reshape(terms.size1_out(1), 1))


def _rates(dynamics: ca.Function, w: ca.DM, t, x, extra) -> tuple:
    """The DAE's (ode, alg) at z = 0: theta_dot first in ode, the rows (1 - w) S Phi_c and
    (1 - w) S d/dt Phi_c in alg."""
    zeros = (ca.SX if isinstance(x, ca.SX) else ca.MX).zeros(2 * w.numel())
    return dynamics(t, x, zeros, w, *extra)


def _function(name: str, like: ca.Function, inputs: list, output, out_name: str
              ) -> ca.Function:
    """inputs -> output (named as `like`'s inputs), its common subexpressions shared in SX."""
    outputs = ca.cse([output]) if isinstance(output, ca.SX) else [output]
    names = ["t", "x", *(like.name_in(k) for k in range(2, len(inputs)))]
    return ca.Function(name, inputs, outputs, names, [out_name])
