"""The loops' ODE and projection (formulations.loop_ode) of a bundle's joint system, as
`method: dop853` integrates a joint system with loops: built once per row mask and joint
system and kept in the run's workspace.

- A joint system whose DAE is SX (an interpreted bundle): one SX graph each, over the
  bundle's IR (saddle_terms) and the system's DAE.
- A parametric library's joint system (functions.joint_functions, bound to this bundle's
  values, with no derivatives for the projection to take through it): the SX graphs over the
  symbols of the model data (model.parametric.split) compiled once per structure and bound to
  this bundle's data; without a compiler, the SX over the bundle's numeric IR, interpreted.
- A controller's joint system (runtime.controller: functions.joint_functions bound to the
  controller, no parametric library), whose forces the bundle's IR does not hold: the ODE from
  the system's own DAE and acceleration system (loop_ode.consistent_ode), the projection
  (geometry and masses only) from the IR's SX.
- A compiled bundle's: the SX graphs of the IR's joint system compiled into a library of their
  own, cached under the bundle's library key, the mask and the projection's iterations
  (backends.library.compile_keyed: a warm cache builds no graph), or under their content for
  a bundle without a key.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from casmech.equations.functions import SystemFunctions
from casmech.errors import AnalysisError, UsageError
from casmech.formulations.joint_constants import DATA
from casmech.formulations.joint_start import Loops
from casmech.formulations.joint_system import JointSystem, build, saddle_terms
from casmech.formulations.tree import spanning_tree
from casmech.runtime import dop853
from casmech.runtime.memo import kept
from casmech.runtime.workspace import KINDS, Workspace

if TYPE_CHECKING:  # (the loops' ODE is imported where it is built or loaded)
    from casmech.formulations import loop_ode

NAMES = ("joint_loop_ode", "joint_loop_project")  # the compiled library's functions


def loop_ode_of(functions: SystemFunctions, system: JointSystem, mask,
                workspace: Workspace, derived: dict | None = None) -> loop_ode.LoopODE:
    """The loops' ODE and projection of `system` (a bundle's, with loops) with the DAE's row
    mask `mask`, kept in `workspace` (module docstring) and in `derived`, the entries of the
    start whose mask it is (runtime.joint_dynamics._kept_start), found there without hashing
    a CasADi Function."""
    found = None if derived is None else derived.get("loop_ode")
    if found is None:
        mask = np.asarray(mask, float)
        found = workspace.kept("loop_ode", (mask.tobytes(), system.dynamics),
                               lambda: _made(functions, system, mask))
        if derived is not None:
            derived["loop_ode"] = found
    return found


def _made(functions: SystemFunctions, system: JointSystem, mask: np.ndarray) -> loop_ode.LoopODE:
    from casmech.formulations import loop_ode

    n_theta = system.layout.n_theta
    if functions.joint_functions is not None and functions.parametric is None:
        # a controller's system (runtime.controller): its forces only in its own functions
        terms, built = saddle_terms(functions.ir, system.tree), build(functions.ir, system.tree)
        return loop_ode.LoopODE(
            loop_ode.consistent_ode(system.acceleration_system, system.dynamics, mask),
            loop_ode.projection(terms, built.dynamics, n_theta, mask), n_theta)
    if system.dynamics.is_a("SXFunction"):
        return loop_ode.build(saddle_terms(functions.ir, system.tree), system.dynamics,
                              n_theta, mask)
    if functions.joint_functions is not None:
        try:
            return loop_ode.LoopODE(*_parametric(functions, system, mask), n_theta)
        except (AnalysisError, UsageError, OSError):  # no compiler: the SX, interpreted
            return loop_ode.LoopODE(*_symbolic(functions, system, mask).values(), n_theta)
    compiled = _compiled(functions, system, mask)
    return loop_ode.LoopODE(compiled[NAMES[0]], compiled[NAMES[1]], n_theta)


def _parametric(functions: SystemFunctions, system: JointSystem, mask: np.ndarray) -> list:
    """A parametric library's loop ODE and projection: compiled over the model data's symbols
    (model.parametric.split) once per structure, mask and iterations (backends.library.
    compile_keyed), each bound to this bundle's data, its first output (backends.parametric.
    bind: the form runtime.dop853's C driver takes)."""
    from casmech.backends.build import Toolchain
    from casmech.backends.library import compile_keyed
    from casmech.backends.parametric import bind
    from casmech.formulations import loop_ode
    from casmech.model.parametric import split

    parts = split(functions.ir)

    def make():
        # the tree of the symbolic IR: a numeric IR's tree holds this bundle's numbers, which
        # the library (shared by every value of the structure) must not
        tree = spanning_tree(parts.ir)
        symbolic = build(parts.ir, tree, data=parts.symbols)
        t, x = ca.SX.sym("t"), ca.SX.sym("x", system.layout.n_x)
        z, p = (ca.SX.sym(name, symbolic.dynamics.sparsity_in(name)) for name in ("z", "p"))
        ode, alg = symbolic.dynamics(t, x, z, p, symbolic.data(parts.symbols))
        dae = ca.Function("dae", [t, x, z, p, parts.symbols], [ode, alg],
                          ["t", "x", "z", "p", DATA], ["ode", "alg"])
        built = loop_ode.build(saddle_terms(parts.ir, tree, data=parts.symbols), dae,
                               system.layout.n_theta, mask)
        return dict(zip(NAMES, (built.ode, built.project), strict=True)), {}, Toolchain()

    content = {"kind": "joint loop ode (parametric)", "signature": parts.signature,
               "mask": mask.tolist(), "iterations": loop_ode.POSITION_ITERATIONS}
    compiled = compile_keyed(content, make)
    return [bind(compiled[name], parts.values, first=True) for name in NAMES]


def _symbolic(functions: SystemFunctions, system: JointSystem, mask) -> dict:
    """The SX graphs of the IR's joint system, by library name."""
    from casmech.formulations import loop_ode

    dynamics = build(functions.ir, system.tree).dynamics
    built = loop_ode.build(saddle_terms(functions.ir, system.tree), dynamics,
                           system.layout.n_theta, mask)
    return dict(zip(NAMES, (built.ode, built.project), strict=True))


def _compiled(functions: SystemFunctions, system: JointSystem, mask: np.ndarray) -> dict:
    from casmech.backends.build import Toolchain
    from casmech.backends.library import compile_functions, compile_keyed
    from casmech.formulations import loop_ode

    if functions.library_key is None:
        return compile_functions(_symbolic(functions, system, mask))
    content = {"kind": "joint loop ode", "bundle": functions.library_key,
               "mask": mask.tolist(), "iterations": loop_ode.POSITION_ITERATIONS}
    return compile_keyed(content, lambda: (_symbolic(functions, system, mask), {},
                                           Toolchain()))


def loop_integrator(loop: loop_ode.LoopODE, options: dict, key, workspace: Workspace
               ) -> dop853.Dop853:
    """DOP853 on the loops' ODE with their projection after every accepted step (and at every
    output point: runtime.dop853), from a run's integrator options (dop853.from_options),
    kept in `workspace` by the ODE and `key` (the options as a key)."""
    return workspace.kept("dop853", (loop.ode, loop.project, key), lambda: replace(
        dop853.from_options(loop.ode, options), project=loop.project))


def dop853_of(system: JointSystem, loop: loop_ode.LoopODE | None, options: dict, key,
              workspace: Workspace, derived: dict | None = None) -> dop853.Dop853:
    """DOP853 of a joint run from its integrator options (`key`: them as a key): over the
    tree's ODE, or with loops over `loop` (loop_integrator); kept in `workspace` by the ODE and
    key, and by key alone in `derived`, the entries of the run's start (runtime.joint_dynamics.
    _kept_start), where a repeated run finds it without hashing a CasADi Function."""
    def found() -> dop853.Dop853:
        if system.n_cut:
            return loop_integrator(loop, options, key, workspace)
        return workspace.kept("dop853", (system.dynamics, key),
                              lambda: dop853.from_options(system.dynamics, options))

    if derived is None:
        return found()
    return kept(derived.setdefault("dop853", {}), key, found, KINDS["dop853"])


def loop_algebraic(loops: Loops, times, states: np.ndarray, solved: bool) -> np.ndarray:
    """The DAE's algebraic states z = [lam; mu] at the states' columns, as the results rows
    read them: zeros where the rows solve the loops themselves (runtime.joint_rows: `solved`)
    or there are none, else each column's consistent multipliers (Loops.z)."""
    if solved or not loops.n_z:
        return np.zeros((loops.n_z, states.shape[1]))
    times = np.ravel(times)[:states.shape[1]]
    return np.column_stack([loops.z(t, x) for t, x in zip(times, states.T, strict=True)])
