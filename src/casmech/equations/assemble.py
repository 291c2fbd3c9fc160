"""The constraint system of a model over given symbols (a Coordinates): the builder's rows
(equations.system, evaluated inline) as expressions, for callers that write functions of their
own over them (casmech.optimal). The bundle's functions are equations.functions'.

`q = [r_1..r_nb, p_1..p_nb]`; ground's pose is constant in every row (GROUND_POSE).
"""

from __future__ import annotations

from functools import cached_property
from typing import TYPE_CHECKING

import casadi as ca

from casmech.core.records import record
from casmech.equations.derivatives import GROUND_POSE
from casmech.equations.evaluation import Evaluation
from casmech.equations.row_kernels import driver_value
from casmech.equations.symbols import Coordinates
from casmech.model.ir import ModelIR

if TYPE_CHECKING:  # (the builder is imported where a System is made: system_over)
    from casmech.equations.system import System

__all__ = ["GROUND_POSE", "ConstraintSystem", "Coordinates", "build_constraints",
           "driver_value", "system_over"]


def system_over(ir: ModelIR, x: Coordinates, lam=None, scale=None) -> System:
    """The builder's System of `ir` evaluated inline over the symbols of x (and the multipliers
    lam, the drivers' scale s: fresh symbols unless given). The IR's numbers may be symbols
    (they stay in the expressions)."""
    from casmech.equations.system import Symbols, System

    m = len(ir.primitives) + ir.n_bodies
    v, v_dot = ca.SX.sym("v", 6 * ir.n_bodies), ca.SX.sym("v_dot", 6 * ir.n_bodies)
    symbols = Symbols(x.t, x.q, x.q_dot, x.q_ddot, ca.SX.sym("lam", m) if lam is None else lam,
                      ca.SX.sym("s") if scale is None else scale, v, v_dot)
    return System(ir, Evaluation.of(True), symbols)


@record
class ConstraintSystem:
    """Phi, phi_q, nu (and the rest when first read) of one model over x."""

    ir: ModelIR
    x: Coordinates
    system: System

    @property
    def phi(self) -> ca.SX:
        return self.system.constraints["phi"]

    @property
    def phi_with_ground(self) -> ca.SX:
        """phi (what eom.reactions takes; the reactions come from the rows' kernels)."""
        return self.phi

    @property
    def phi_q(self) -> ca.SX:
        return self.system.constraints["phi_q"]

    @property
    def nu(self) -> ca.SX:
        return self.system.constraints["nu"]

    @property
    def gamma(self) -> ca.SX:
        return self.system.constraints["gamma"]

    @property
    def scale(self) -> ca.SX:
        """The continuation parameter of the drivers (assembly)."""
        return self.system.x.s

    @property
    def phi_r(self) -> ca.SX:  # (m, 3 nb)
        return self.system.variations[:, :3 * self.x.n_bodies]

    @property
    def pi_bar(self) -> ca.SX:  # (m, 3 nb)
        return self.system.variations[:, 3 * self.x.n_bodies:]

    @cached_property
    def phi_scaled(self) -> ca.SX:
        return self.system.scaled["phi"]

    @cached_property
    def phi_q_scaled(self) -> ca.SX:
        return self.system.scaled["phi_q"]


def build_constraints(ir: ModelIR) -> ConstraintSystem:
    x = Coordinates.create(ir.n_bodies)
    return ConstraintSystem(ir, x, system_over(ir, x))
