"""Every system function of equations.functions, built from mapped kernels (MX over SX kernels):
the bundle code generation compiles. Same names, inputs, outputs and sparsity as the unrolled
SX bundle, equal values (tests/codegen/test_mapped.py), and C whose size does not grow with the
number of bodies, joints or force elements (only index tables and data do).

The DAE residuals are not built over this bundle (formulations.dae over it is an MX graph whose
Jacobian CasADi evaluates by a forward sweep per colour, slower than the interpreted SX:
docs/decisions/codegen-element-residuals.md) but as sums of elements: formulations.residuals.
"""

from __future__ import annotations

import casadi as ca

from casmech.equations.mapped import bodies, forces, kernels
from casmech.model.ir import ModelIR


def _function(name, inputs: dict, outputs: dict) -> ca.Function:
    return ca.Function(name, list(inputs.values()), list(outputs.values()),
                       list(inputs), list(outputs), {"max_num_dir": kernels.MAX_DIRECTIONS})


def _symbols(ir: ModelIR) -> dict:
    nb, m = ir.n_bodies, len(ir.primitives) + ir.n_bodies
    n = 7 * nb
    return {"t": ca.MX.sym("t"), "q": ca.MX.sym("q", n), "q_dot": ca.MX.sym("q_dot", n),
            "q_ddot": ca.MX.sym("q_ddot", n), "lam": ca.MX.sym("lam", m), "s": ca.MX.sym("s"),
            "v": ca.MX.sym("v", 6 * nb), "v_dot": ca.MX.sym("v_dot", 6 * nb)}


def rp_functions(ir: ModelIR, x: dict) -> list[ca.Function]:
    """The r-p bundle, in equations.functions' order."""
    t, q, q_dot, nb = x["t"], x["q"], x["q_dot"], ir.n_bodies
    c = kernels.rp_constraints(ir, t, q, q_dot)
    scaled = kernels.rp_constraints(ir, t, q, q_dot, scale=x["s"])
    variation = kernels.variations(ir, t, q)
    element_forces, spring_potential = forces.applied(ir, t, q, q_dot)
    kinetic, gravity_potential = bodies.energy(ir, q, q_dot)
    force, torque = kernels.reactions(ir, t, q, x["lam"])
    motor_force, motor_torque = forces.motor_reactions(ir, t, q, q_dot)
    force, torque = force + motor_force, torque + motor_torque
    omega, alpha = bodies.body_rates(ir, q, q_dot, x["q_ddot"])
    generalized = bodies.gravity(ir) + element_forces + bodies.quadratic_velocity(ir, q, q_dot)
    return [
        _function("phi", {"t": t, "q": q}, {"phi": c["phi"]}),
        _function("phi_q", {"t": t, "q": q}, {"phi_q": c["phi_q"]}),
        _function("nu", {"t": t, "q": q}, {"nu": c["nu"]}),
        _function("gamma", {"t": t, "q": q, "q_dot": q_dot}, {"gamma": c["gamma"]}),
        _function("variations", {"t": t, "q": q}, {"phi_r": variation[:, :3 * nb],
                                                   "pi_bar": variation[:, 3 * nb:]}),
        _function("phi_scaled", {"t": t, "q": q, "s": x["s"]},
                  {"phi": scaled["phi"], "phi_q": scaled["phi_q"]}),
        _function("mass_matrix", {"q": q}, {"mass_matrix": bodies.mass_matrix(ir, q)}),
        _function("generalized_forces", {"t": t, "q": q, "q_dot": q_dot},
                  {"generalized_forces": ca.densify(generalized)}),
        _function("energy", {"t": t, "q": q, "q_dot": q_dot},
                  {"kinetic": kinetic, "potential": spring_potential + gravity_potential}),
        _function("reactions", {"t": t, "q": q, "q_dot": q_dot, "lam": x["lam"]},
                  {"force": force, "torque": torque}),
        _function("body_rates", {"q": q, "q_dot": q_dot, "q_ddot": x["q_ddot"]},
                  {"omega": omega, "alpha": alpha}),
        _function("element_outputs", {"t": t, "q": q, "q_dot": q_dot},
                  {"values": forces.element_outputs(ir, t, q, q_dot)}),
    ]


def romega_functions(ir: ModelIR, x: dict) -> list[ca.Function]:
    """The romega_* functions of equations.romega.definitions, in its order."""
    t, q, v, nb = x["t"], x["q"], x["v"], ir.n_bodies
    joint_rows = len(ir.primitives)
    q_dot = bodies.romega_q_dot(ir, q, v)
    applied = bodies.gravity(ir) + forces.applied(ir, t, q, q_dot)[0]
    generalized = ca.vertcat(applied[:3 * nb], bodies.romega_torques(ir, q, v, applied))
    nu = kernels.rp_constraints(ir, t, q, ca.MX(7 * nb, 1))["nu"][:joint_rows] if joint_rows \
        else ca.MX(0, 1)
    return [
        _function("romega_mass", {"q": q}, {"mass": bodies.romega_mass(ir)}),
        _function("romega_forces", {"t": t, "q": q, "v": v},
                  {"forces": ca.densify(generalized)}),
        _function("romega_jacobian", {"t": t, "q": q},
                  {"jacobian": kernels.variations(ir, t, q, joint_rows_only=True)}),
        _function("romega_nu", {"t": t, "q": q}, {"nu": nu}),
        _function("romega_gamma", {"t": t, "q": q, "v": v},
                  {"gamma": kernels.romega_gamma(ir, t, q, v)}),
        _function("romega_q_dot", {"q": q, "v": v}, {"q_dot": q_dot}),
        _function("romega_to_rp", {"q": q, "v": v, "v_dot": x["v_dot"]},
                  {"q_dot": q_dot, "q_ddot": bodies.romega_q_ddot(ir, q, v, x["v_dot"])}),
    ]


def mapped_functions(ir: ModelIR) -> dict[str, ca.Function]:
    """name -> MX Function over mapped kernels, as equations.functions.build_functions names
    them."""
    x = _symbols(ir)
    return {f.name(): f for f in rp_functions(ir, x) + romega_functions(ir, x)}
