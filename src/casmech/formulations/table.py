"""The two body-coordinate forms of the equations of motion, as a table of system-function
names (BODY_FORMS; the registered formulations are formulations.registry.FORMULATIONS).

Either form reads M v_dot + P^T lam = F, P v_dot = gamma, with velocity constraint P v = nu:
r-p (Euler parameters, v = q_dot, every row of Phi including normalization) and r-omega
(Newton-Euler, v = [r_dot; omega_bar], joint rows only, q_dot = q_dot(q, v)).
"""

from __future__ import annotations

from casmech.core.records import record


@record
class BodyForm:
    """Which system functions play M, F, P, gamma and nu; q_dot(q, v) (None: v is q_dot)."""

    mass: str
    forces: str
    jacobian: str
    gamma: str
    nu: str
    q_dot: str | None


BODY_FORMS = {
    "rp": BodyForm("mass_matrix", "generalized_forces", "phi_q", "gamma", "nu", None),
    "romega": BodyForm("romega_mass", "romega_forces", "romega_jacobian", "romega_gamma",
                       "romega_nu", "romega_q_dot"),
}
