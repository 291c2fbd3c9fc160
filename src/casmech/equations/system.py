"""THE builder: every system function of a model, each quantity defined once over the kernels
of its rows (equations.rows), bodies (equations.bodies) and force elements (equations.forces),
evaluated inline (SX) or mapped (MX) by one switch (equations.evaluation.Evaluation).

`System(ir, evaluation)` holds the model's symbols and builds each quantity when first read;
`DEFINITIONS` defines the bundle's functions (inputs and outputs over a System), in the order
every bundle lists them (equations.bundle_names.NAMES).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cached_property

import casadi as ca

from casmech.core.records import record
from casmech.equations import bodies, forces, inline, rows
from casmech.equations.bundle_names import NAMES
from casmech.equations.evaluation import Evaluation
from casmech.equations.layout import Layout
from casmech.model.ir import ModelIR


@record
class Symbols:
    """The functions' inputs: time, coordinates and rates, multipliers, the drivers' scale, the
    r-omega velocities."""

    t: object
    q: object
    q_dot: object
    q_ddot: object
    lam: object
    s: object
    v: object
    v_dot: object

    @staticmethod
    def create(ir: ModelIR, sym) -> Symbols:
        nb, m = ir.n_bodies, len(ir.primitives) + ir.n_bodies
        n = 7 * nb
        return Symbols(sym.sym("t"), sym.sym("q", n), sym.sym("q_dot", n), sym.sym("q_ddot", n),
                       sym.sym("lam", m), sym.sym("s"), sym.sym("v", 6 * nb),
                       sym.sym("v_dot", 6 * nb))


class System:
    """The quantities of one model over its kernels, built when first read."""

    def __init__(self, ir: ModelIR, ev: Evaluation, symbols: Symbols | None = None):
        self.ir, self.ev = ir, ev
        self.x = symbols or Symbols.create(ir, ev.sym)

    @cached_property
    def grounded(self) -> tuple | None:
        """Inline: the rows with ground's pose symbolic (inline.grounded), which the
        constraints and the reactions share; None when mapped."""
        if not self.ev.inline:
            return None
        return inline.grounded(self.ir, self.ev, rows.groups(self.ir, Layout(self.ir.n_bodies),
                                                             self.ev), self.x.t, self.x.q)

    @cached_property
    def constraints(self) -> dict:
        """phi, phi_q, nu, gamma."""
        x = self.x
        return rows.constraints(self.ir, self.ev, x.t, x.q, x.q_dot, grounded=self.grounded)

    @cached_property
    def scaled(self) -> dict:
        """phi and phi_q with the drivers scaled by s (assembly's continuation)."""
        x = self.x
        return rows.constraints(self.ir, self.ev, x.t, x.q, scale=x.s)

    @property
    def _derived(self) -> dict | None:
        """The constraints the inline evaluation's variations differentiate (None: mapped)."""
        return self.constraints if self.ev.inline else None

    @cached_property
    def variations(self):
        """[Phi_r, Pi_bar] of every row (rows of phi x 6 nb)."""
        return rows.variations(self.ir, self.ev, self.x.t, self.x.q, derived=self._derived)

    @cached_property
    def applied(self) -> tuple:
        """(gravity and the force elements' generalized forces, their potential)."""
        x = self.x
        return forces.applied(self.ir, self.ev, x.t, x.q, x.q_dot,
                              bodies.gravity(self.ir, self.ev))

    def mass_matrix(self):
        return bodies.mass_matrix(self.ir, self.ev, self.x.q)

    def generalized_forces(self):
        """Gravity, the force elements and the quadratic-velocity force (r-p)."""
        x = self.x
        return ca.densify(self.applied[0]
                          + bodies.quadratic_velocity(self.ir, self.ev, x.q, x.q_dot))

    def energy(self) -> tuple:
        """(kinetic, potential: the elements' and gravity's)."""
        kinetic, gravity = bodies.energy(self.ir, self.ev, self.x.q, self.x.q_dot)
        return kinetic, self.applied[1] + gravity

    def reactions(self) -> tuple:
        """(force, torque) each joint exerts on its body_j (3 x joints): its rows' (global,
        torque about body_i's joint point), its effort motor's and its stop's."""
        x = self.x
        force, torque = rows.reactions(self.ir, self.ev, x.t, x.q, x.lam, self.grounded)
        motor_force, motor_torque = forces.motor_reactions(self.ir, self.ev, x.t, x.q, x.q_dot)
        return force + motor_force, torque + motor_torque

    def body_rates(self) -> tuple:
        return bodies.body_rates(self.ir, self.ev, self.x.q, self.x.q_dot, self.x.q_ddot)

    def element_outputs(self):
        x = self.x
        return forces.element_outputs(self.ir, self.ev, x.t, x.q, x.q_dot)

    # --- r-omega (Newton-Euler) form: v = [r_dot; omega_bar], the joint rows only ---------

    @cached_property
    def romega_q_dot(self):
        return bodies.romega_q_dot(self.ir, self.ev, self.x.q, self.x.v)

    def romega_forces(self):
        """[F; n_bar - omega_bar~ J_bar omega_bar], F the r-p applied forces at q_dot(q, v)."""
        x, nb = self.x, self.ir.n_bodies
        applied = forces.applied(self.ir, self.ev, x.t, x.q, self.romega_q_dot,
                                 bodies.gravity(self.ir, self.ev))[0]
        torques = bodies.romega_torques(self.ir, self.ev, x.q, x.v, applied)
        return ca.densify(ca.vertcat(applied[:3 * nb], torques))

    def romega_jacobian(self):
        return rows.variations(self.ir, self.ev, self.x.t, self.x.q, True, self._derived)

    def romega_nu(self):
        joint_rows = len(self.ir.primitives)
        if not joint_rows:
            return self.ev.sym(0, 1)
        derived = self._derived or rows.constraints(self.ir, self.ev, self.x.t, self.x.q)
        return derived["nu"][:joint_rows]

    def romega_gamma(self):
        x = self.x
        return rows.romega_gamma(self.ir, self.ev, x.t, x.q, x.v, self.romega_q_dot,
                                 self._derived)

    def romega_q_ddot(self):
        return bodies.romega_q_ddot(self.ir, self.ev, self.x.q, self.x.v, self.x.v_dot)


def _tq(s: System) -> dict:
    return {"t": s.x.t, "q": s.x.q}


def _tqv(s: System) -> dict:
    return {"t": s.x.t, "q": s.x.q, "q_dot": s.x.q_dot}


def _named(names: tuple[str, ...], values) -> dict:
    return dict(zip(names, values, strict=True))


# name -> its (inputs, outputs) over a System, in the bundle's order (bundle_names.NAMES)
DEFINITIONS: dict[str, Callable[[System], tuple[dict, dict]]] = {
    "phi": lambda s: (_tq(s), {"phi": s.constraints["phi"]}),
    "phi_q": lambda s: (_tq(s), {"phi_q": s.constraints["phi_q"]}),
    "nu": lambda s: (_tq(s), {"nu": s.constraints["nu"]}),
    "gamma": lambda s: (_tqv(s), {"gamma": s.constraints["gamma"]}),
    "variations": lambda s: (_tq(s), {"phi_r": s.variations[:, :3 * s.ir.n_bodies],
                                      "pi_bar": s.variations[:, 3 * s.ir.n_bodies:]}),
    "phi_scaled": lambda s: (_tq(s) | {"s": s.x.s},
                             {"phi": s.scaled["phi"], "phi_q": s.scaled["phi_q"]}),
    "mass_matrix": lambda s: ({"q": s.x.q}, {"mass_matrix": s.mass_matrix()}),
    "generalized_forces": lambda s: (_tqv(s), {"generalized_forces": s.generalized_forces()}),
    "energy": lambda s: (_tqv(s), _named(("kinetic", "potential"), s.energy())),
    "reactions": lambda s: (_tqv(s) | {"lam": s.x.lam},
                            _named(("force", "torque"), s.reactions())),
    "body_rates": lambda s: ({"q": s.x.q, "q_dot": s.x.q_dot, "q_ddot": s.x.q_ddot},
                             _named(("omega", "alpha"), s.body_rates())),
    "element_outputs": lambda s: (_tqv(s), {"values": s.element_outputs()}),
    "romega_mass": lambda s: ({"q": s.x.q}, {"mass": bodies.romega_mass(s.ir, s.ev)}),
    "romega_forces": lambda s: ({"t": s.x.t, "q": s.x.q, "v": s.x.v},
                                {"forces": s.romega_forces()}),
    "romega_jacobian": lambda s: (_tq(s), {"jacobian": s.romega_jacobian()}),
    "romega_nu": lambda s: (_tq(s), {"nu": s.romega_nu()}),
    "romega_gamma": lambda s: ({"t": s.x.t, "q": s.x.q, "v": s.x.v},
                               {"gamma": s.romega_gamma()}),
    "romega_q_dot": lambda s: ({"q": s.x.q, "v": s.x.v}, {"q_dot": s.romega_q_dot}),
    "romega_to_rp": lambda s: ({"q": s.x.q, "v": s.x.v, "v_dot": s.x.v_dot},
                               {"q_dot": s.romega_q_dot, "q_ddot": s.romega_q_ddot()}),
}
if tuple(DEFINITIONS) != NAMES:
    raise ImportError("equations.system.DEFINITIONS and equations.bundle_names.NAMES name the "
                      "bundle's functions differently")


# Functions merged inline at any size: their kernels repeat a per-body term (q_dot's p_dot in
# q_ddot's), which the merge removes in time linear in the bodies.
MERGED = frozenset({"romega_to_rp"})
# The functions only a results row reads (runtime.results.row_function), evaluated once per
# output row.
RESULTS = ("reactions", "body_rates", "energy", "element_outputs")
# Functions never merged: a results row's terms, where the merge costs about as much as
# building them and saves a fraction of a row's evaluation.
UNMERGED = frozenset(RESULTS)


def function(system: System, name: str) -> ca.Function:
    """The bundle's function `name` over a System."""
    inputs, outputs = DEFINITIONS[name](system)
    merged = True if name in MERGED else False if name in UNMERGED else None
    return system.ev.function(name, inputs, outputs, merged)
