"""The start of an FMU's run at the model's own values, as `casmech run` computes it.

The state x0 = [theta; u] of the joint formulation (the file's pose assembled and its
velocities projected, mapped to joint coordinates by the registered joint formulation's Start),
the signs that align the tree's Euler parameters with the r-p state, and which loop-closure
rows depend on the others there (masked out of the FMU's equations, as the joint DAE masks
them). The FMU starts from x0 and solves the same closest-point problem in joint coordinates
for other parameter values (fmu.system), so at the model's values it starts exactly where
`casmech run` does.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.core.records import record
from casmech.elements.coordinate_kinds import BY_MODE
from casmech.equations.assemble import Coordinates
from casmech.equations.functions import build_functions
from casmech.equations.motors import coordinate_and_value
from casmech.errors import UsageError
from casmech.fmu.model import Input
from casmech.formulations.registry import FORMULATIONS
from casmech.formulations.tree import spanning_tree
from casmech.model.lower import lower
from casmech.runtime import assembly
from casmech.schema.resolved import ResolvedModel


@record
class Start:
    t0: float
    x0: np.ndarray
    signs: np.ndarray  # +1/-1 per body (the Start's p after the mask)
    mask: np.ndarray  # 1 for the cut rows masked out (dependent at t0), else 0
    inputs: np.ndarray  # each input's start: its motor law at the start state (controls: 0)
    q0: np.ndarray
    q_dot0: np.ndarray


def start(model: ResolvedModel, inputs: tuple[Input, ...], t0: float = 0.0) -> Start:
    """The numeric start of the model at its values (module docstring)."""
    ir = lower(model)
    functions = build_functions(ir)
    tree = spanning_tree(ir)
    if tree.floating_loops:
        raise UsageError(f"{model.file}: a loop closes through a floating body; its joint "
                         "coordinates are not an ODE the FMU can integrate (casmech run "
                         "integrates it in the r-p DAE)")
    if tree.couplings:
        names = ", ".join(f"'{joint.name}'" for joint in tree.couplings)
        raise UsageError(f"{model.file}: the FMU's equations (a tree's joint coordinates) do "
                         f"not take couplings of joint coordinates ({names}); casmech run "
                         "integrates them (formulation auto)")
    held = [joint.name for joint in ir.joints if joint.initial]
    if held:
        raise UsageError(f"{model.file}: joints' initial: values ({', '.join(held)}) are not "
                         "in the FMU, which starts from the bodies' poses in the file; write "
                         "the pose there (casmech run holds the values)")
    formulation = FORMULATIONS["joint"]
    system = formulation.system(functions)
    q0, q_dot0 = assembly.initial_state(functions, t0)
    begin = formulation.start(functions, system, t0, q0, q_dot0)  # p = [mask; signs]
    m = system.n_z // 2  # z = [lam; mu] of the cut rows
    values = [_law(ir, i, t0, q0, q_dot0) for i in inputs]
    return Start(t0, begin.x, begin.p[m:], begin.p[:m], np.array(values, float), q0, q_dot0)


def _law(ir, entry: Input, t0: float, q0, q_dot0) -> float:
    """The motor law of an input at the start state (an `ocp:` control without a motor: 0)."""
    kind = BY_MODE[entry.kind][0].effort  # the effort motor's ForceIR type
    motor = next((m for m in ir.motors if m.name == entry.joint and m.type == kind), None)
    if motor is None:
        return 0.0
    x = Coordinates.create(ir.n_bodies)
    _, value = coordinate_and_value(motor, x)
    law = ca.Function("law", [x.t, x.q, x.q_dot], [x.ground_fixed(value)])
    return float(law(t0, q0, q_dot0))
