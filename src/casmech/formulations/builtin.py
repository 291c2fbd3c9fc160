"""The built-in formulations as implementations of formulations.protocol: rp and romega (body
coordinates: the DAEs of formulations.dae over the function names of formulations.table) and
joint (joint coordinates: the tree's ODE or the loops' DAE of formulations.joint_system, started
by formulations.joint_start; for optimal control formulations.joint_control)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from casmech.core import euler
from casmech.core.options import STABILIZATIONS, DynamicsSolver, LinearAlgebra
from casmech.core.records import record
from casmech.equations.checks import structure
from casmech.equations.functions import SystemFunctions
from casmech.formulations.joint_start import Loops, initial_state, quaternion_signs
from casmech.formulations.joint_system import JointSystem, build, labels
from casmech.formulations.protocol import (
    DEFAULT,
    Formulation,
    Start,
    States,
    System,
    indexed,
)
from casmech.formulations.tree import spanning_tree
from casmech.model.ir import ModelIR

if TYPE_CHECKING:
    from casmech.formulations.joint_control import JointControl


def velocities(functions: SystemFunctions, name: str, q, q_dot) -> np.ndarray:
    """The formulation's v from r-p velocities: omega_bar = 2 G(p) p_dot for r-omega."""
    if name == "rp":
        return np.array(q_dot, float)
    nb = functions.n_bodies
    omega_bar = [2 * euler.numeric(euler.g_matrix, q[3 * nb + 4 * k:3 * nb + 4 * k + 4])
                 @ q_dot[3 * nb + 4 * k:3 * nb + 4 * k + 4] for k in range(nb)]
    return np.concatenate([q_dot[:3 * nb], *omega_bar])


def row_scales(functions: SystemFunctions, name: str, t, q) -> tuple[np.ndarray, np.ndarray]:
    """(s, s_phi): the DAEs' row scales (formulations.dae), inverse row norms of P and of
    Phi_q at (t, q)."""
    from casmech.formulations.table import BODY_FORMS

    form = BODY_FORMS[name]
    jacobian = functions.matrix(form.jacobian, t, q)
    phi_q = jacobian if form.jacobian == "phi_q" else functions.matrix("phi_q", t, q)
    return 1 / np.linalg.norm(jacobian, axis=1), 1 / np.linalg.norm(phi_q, axis=1)


def masked_rows(functions: SystemFunctions, name: str, t, q,
                limits: LinearAlgebra = DEFAULT.assembly.linear_algebra) -> np.ndarray:
    """1 for every row of P dropped from the DAE, else 0: the rows equations.checks.structure
    finds redundant at (t, q) (the same joint rows in both formulations; r-p rows are ordered
    as Phi's, r-omega's are Phi's joint rows)."""
    from casmech.formulations import dae

    keep = np.zeros(functions.n_rows)
    keep[list(structure(functions, t, q, limits).independent)] = 1.0
    return 1.0 - keep[:dae.sizes(functions.functions, name)[2]]


@record
class BodyCoordinates(Formulation):
    """rp or romega: x = [q, v], z = [v_dot, lam (scaled), mu (ggl)], p = [t0, w, s (, s_phi),
    d] as formulations.dae writes them; t relative to p[0]."""

    def states(self, functions: SystemFunctions, stabilization: str = "ggl") -> States:
        from casmech.formulations import dae

        n_q, n_v, m = dae.sizes(functions.functions, self.name)
        mu = functions["phi"].size1_out(0) if stabilization == "ggl" else 0
        return States(indexed("q", n_q) + indexed("v", n_v),
                      indexed("v_dot", n_v) + indexed("lam", m) + indexed("mu", mu))

    def residual(self, functions: SystemFunctions, stabilization: str = "ggl") -> ca.Function:
        """formulations.dae's dae_[ggl_]<name>: the bundle's own when it carries it."""
        from casmech.formulations import dae

        return dae.residual(functions.functions, self.name, stabilization)

    def library_stabilizations(self) -> tuple[str, ...]:
        return STABILIZATIONS  # formulations.dae's, read on every run (backends.deferred)

    def system(self, functions: SystemFunctions, stabilization: str = "ggl") -> System:
        from casmech.formulations import dae
        from casmech.formulations.table import BODY_FORMS

        residual = self.residual(functions, stabilization)
        n_q, n_v, m = dae.sizes(functions.functions, self.name)
        form = BODY_FORMS[self.name]
        tau, x = ca.MX.sym("t"), ca.MX.sym("x", n_q + n_v)
        z, p = ca.MX.sym("z", residual.size1_in(2)), ca.MX.sym("p", residual.size1_in(3))
        q, v, v_dot = x[:n_q], x[n_q:], z[:n_v]
        lam = p[1 + m:1 + 2 * m] * z[n_v:n_v + m]  # the true multipliers
        if form.q_dot is None:
            q_dot, q_ddot = v, v_dot
        else:  # the normalization rows carry no reaction
            (q_dot, q_ddot), lam = functions["romega_to_rp"](q, v, v_dot), ca.vertcat(
                lam, ca.MX(functions.n_rows - m, 1))
        rows = ca.Function(f"rows_{self.name}", [tau, x, z, p], [q, q_dot, q_ddot, lam],
                           ["t", "x", "z", "p"], ["q", "q_dot", "q_ddot", "lam"])
        return System(residual, rows, time_offset=0)

    def start(self, functions: SystemFunctions, system: System, t0: float, q: np.ndarray,
              q_dot: np.ndarray) -> Start:
        """[q, v] with the consistent (v_dot, lam / s) of the masked, scaled rows (the rows
        equations.checks.structure finds redundant at t0 masked; s the inverse row norms)."""
        from casmech.formulations import dae
        from casmech.formulations.table import BODY_FORMS
        from casmech.numerics import kkt

        form = BODY_FORMS[self.name]
        n_q, n_v, m = dae.sizes(functions.functions, self.name)
        v = velocities(functions, self.name, q, q_dot)
        mask = masked_rows(functions, self.name, t0, q)
        s, s_phi = row_scales(functions, self.name, t0, q)
        jacobian = functions.matrix(form.jacobian, t0, q)
        mass, scaled = functions[form.mass](q), ca.DM(s[:, None] * jacobian)
        forces = functions[form.forces](t0, q, v)
        gamma = functions.vector(form.gamma, t0, q, v) * s
        solve = kkt.saddle(mass.sparsity(), scaled.sparsity())
        v_dot, lam = (np.array(out).ravel() for out in solve(mass, scaled, forces, gamma, mask))
        p = [[t0], mask, s]
        if system.n_z > n_v + m:  # ggl: mu, and the scales of Phi's rows
            p.append(s_phi)
        if functions.data is not None:
            p.append(np.asarray(functions.data, float).ravel())
        z = np.zeros(system.n_z)
        z[:n_v + m] = np.concatenate([v_dot, lam])
        return Start(np.concatenate([q, v]), z, np.concatenate(p))

    def integrator_options(self, functions: SystemFunctions, system: System, t: float,
                           x: np.ndarray, z: np.ndarray, p: np.ndarray, rtol: float,
                           atol: float, interval: float,
                           settings: DynamicsSolver = DEFAULT) -> dict:
        """As runtime.dynamics sets them: the algebraic tolerances per group, and with ggl
        the first step from the translations' accelerations."""
        from casmech.formulations import dae
        from casmech.formulations.dae_options import algebraic_tolerances, initial_step

        _, n_v, m = dae.sizes(functions.functions, self.name)
        ggl = system.n_z > n_v + m
        v_dot, lam = z[:n_v], z[n_v:n_v + m]
        floor = settings.algebraic_tolerance if ggl else atol
        out = {"abstolv": [atol] * len(x) + list(algebraic_tolerances(
            rtol, floor, v_dot, lam, len(z), settings.mu_tolerance))}
        if ggl and settings.initial_step is None:
            n = 3 * functions.n_bodies  # the translations lead q and v in both forms
            out["step0"] = initial_step(x[:n], v_dot[:n], rtol, atol, interval)
        return out


@record(eq=False)
class TreeSystem(System):
    """The joint formulation's System, with the JointSystem its start reads."""

    joint: JointSystem | None = None


@record
class JointCoordinates(Formulation):
    """joint: x = [theta; u] of the free tree joints, z = [lam, mu] of the cut joints' rows
    (none on a tree), p = [w (one per cut row), quaternion signs (one per body)]; t
    absolute."""

    def states(self, functions: SystemFunctions, stabilization: str = "ggl") -> States:
        """x's entries by name (formulations.joint_system.labels: `<joint>.angle`, ...)."""
        tree = spanning_tree(functions.ir)
        coordinates, velocities = labels(tree, functions.body_names)
        cut = sum(len(joint.rows) for joint in tree.cut)
        return States(coordinates + velocities, indexed("lam", cut) + indexed("mu", cut))

    def equations(self, ir: ModelIR, data: ca.SX | None = None) -> JointSystem:
        """formulations.joint_system's JointSystem of the model's spanning tree: the ODE or
        DAE, the results row's motion, the loops' start terms, the relative states."""
        return build(ir, spanning_tree(ir), data)

    def controlled(self, ir: ModelIR, data: ca.SX) -> JointControl | None:
        """formulations.joint_control's equations over the JointSystem `equations` builds
        over `data`; None for loops through a floating body (formulations.tree: its joint
        coordinates are its r-p ones plus the recursion's overhead)."""
        from casmech.formulations.joint_control import JointControl

        tree = spanning_tree(ir)
        if tree.floating_loops:
            return None
        return JointControl(build(ir, tree, data), ir, data)

    def system(self, functions: SystemFunctions, stabilization: str = "ggl") -> System:
        joint = self.equations(functions.ir)
        m, nb = joint.n_cut, functions.n_bodies
        t, x = ca.MX.sym("t"), ca.MX.sym("x", joint.layout.n_x)
        z, p = ca.MX.sym("z", 2 * m), ca.MX.sym("p", m + nb)
        if m:
            ode, alg = joint.dynamics(t, x, z, p[:m])
        else:
            ode, alg = joint.dynamics(t, x), ca.MX(0, 1)
        residual = ca.Function("joint", [t, x, z, p], [ode, alg], ["t", "x", "z", "p"],
                               ["ode", "alg"])
        q, q_dot, q_ddot, lam = joint.motion(t, x, z, p[m:])[:4]
        rows = ca.Function("rows_joint", [t, x, z, p], [q, q_dot, q_ddot, lam],
                           ["t", "x", "z", "p"], ["q", "q_dot", "q_ddot", "lam"])
        return TreeSystem(residual, rows, None, joint)

    def start(self, functions: SystemFunctions, system: System, t0: float, q: np.ndarray,
              q_dot: np.ndarray) -> Start:
        """Each tree joint's state at the r-p state, the loops' consistent multipliers with
        the rows dependent at t0 masked, and the quaternion signs."""
        joint = system.joint
        x = initial_state(joint, q, q_dot)
        loops = Loops(joint, t0, x)
        z = loops.z(t0, x)
        signs = quaternion_signs(joint, t0, x, z, q, functions.n_bodies)
        return Start(x, z, np.concatenate([loops.mask, signs]))

    def integrator_options(self, functions: SystemFunctions, system: System, t: float,
                           x: np.ndarray, z: np.ndarray, p: np.ndarray, rtol: float,
                           atol: float, interval: float,
                           settings: DynamicsSolver = DEFAULT) -> dict:
        """The loops' DAE's, as runtime.joint_dynamics sets them (none for a tree's ODE)."""
        from casmech.formulations.dae_options import algebraic_tolerances, initial_step

        joint = system.joint
        if not joint.n_cut:
            return {}
        nb = len(joint.tree.joints)  # every body is the child of one tree joint
        q, _, q_ddot, _ = (np.array(v.full()).ravel()
                           for v in joint.motion(t, x, z, np.ones(nb)))
        n = 3 * nb
        out = {"abstolv": [atol] * len(x) + list(algebraic_tolerances(
            rtol, settings.algebraic_tolerance, np.zeros(0), z[:joint.n_cut], len(z),
            settings.mu_tolerance))}
        out["step0"] = settings.initial_step or initial_step(q[:n], q_ddot[:n], rtol, atol,
                                                             interval)
        return out


BUILT_IN = (BodyCoordinates("rp"), BodyCoordinates("romega"),
            JointCoordinates("joint"))
