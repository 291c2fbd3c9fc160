"""Equations of motion in the r-p form over given symbols (a Coordinates): the builder's
quantities (equations.system, evaluated inline) as expressions, for callers that write functions
of their own over them (the joint formulation's applied forces, casmech.optimal). The bundle's
functions are equations.functions'.

r-p form (Haug 1989, ch. 11): M r_ddot + Phi_r^T lam = F and
4 G^T J_bar G p_ddot + Phi_p^T lam + P^T lam_P = 2 G^T n_bar + 8 G_dot^T J_bar G_dot p.
The force elements' laws by type: equations.force_laws (FORCE_ELEMENTS, INPUT_KINDS).
"""

from __future__ import annotations

from casmech.equations import bodies
from casmech.equations.assemble import system_over
from casmech.equations.force_laws import FORCE_ELEMENTS, INPUT_KINDS, JOINT_ELEMENTS
from casmech.equations.symbols import Coordinates
from casmech.model.ir import ModelIR

__all__ = ["FORCE_ELEMENTS", "INPUT_KINDS", "JOINT_ELEMENTS", "applied_forces", "energy",
           "mass_matrix", "quadratic_velocity", "reactions"]


def mass_matrix(ir: ModelIR, x: Coordinates):
    """blkdiag(m_k I_3 ..., 4 G_k^T J_bar_k G_k ...) (7 nb x 7 nb)."""
    return system_over(ir, x).mass_matrix()


def quadratic_velocity(ir: ModelIR, x: Coordinates):
    """[0; 8 G_dot^T J_bar G_dot p] for every body (G_dot = G(p_dot))."""
    system = system_over(ir, x)
    return bodies.quadratic_velocity(ir, system.ev, x.q, x.q_dot)


def applied_forces(ir: ModelIR, x: Coordinates):
    """(generalized applied forces incl. gravity, the force elements' potential energy)."""
    return system_over(ir, x).applied


def energy(ir: ModelIR, x: Coordinates, spring_potential):
    """(kinetic, potential): 1/2 m v.v + 1/2 w_bar^T J_bar w_bar; -m g.r + spring_potential."""
    system = system_over(ir, x)
    kinetic, gravity = bodies.energy(ir, system.ev, x.q, x.q_dot)
    return kinetic, spring_potential + gravity


def reactions(ir: ModelIR, x: Coordinates, phi_with_ground, lam):
    """Force and torque each joint exerts ON body_j: global, torque about body_i's joint point
    (its rows', plus its motor's and its stop's), from the rows' kernels (phi_with_ground, the
    constraint rows of x, is what callers hold; the kernels rebuild them per joint)."""
    del phi_with_ground
    return system_over(ir, x, lam=lam).reactions()
