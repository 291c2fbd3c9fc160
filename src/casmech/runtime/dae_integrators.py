"""The IDAS integrators of the r-p / r-omega DAEs (formulations.dae), kept in the run's
workspace (runtime.workspace) for later runs.

Creating an integrator over an interpreted (SX) DAE makes CasADi differentiate the residual for
IDAS's Jacobian and analyse its sparsity, a large part of a short run (a compiled DAE brings
its Jacobian). IDAS takes the start's derivative
(init_xdot), its first step (step0) and the algebraic tolerances (abstolv) as options, which
depend on the initial state, so an integrator is kept per DAE, relative output grid and
option values: a run from the same state over the same grid (an analysis repeated, a
benchmark's runs) reuses it, and its results are those of a new one. Whatever depends on the
state cannot be an input instead (docs/decisions/rp-integrators-kept.md: integrating
x - tau x_dot0 lost accuracy, IDAS's own first step failed at rtol 1e-10).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.equations.functions import SystemFunctions
from casmech.formulations import dae
from casmech.runtime.buffers import NamedCall
from casmech.runtime.workspace import Workspace, of


def problem(functions: SystemFunctions, name: str, kind: str,
            workspace: Workspace | None = None) -> dict | ca.Function:
    """The DAE of formulation `name` and stabilization `kind` as casadi.integrator takes it,
    built once per workspace."""
    return of(functions, workspace).kept("dae_problems", (name, kind), lambda: dae.problem(
        dae.residual(functions.functions, name, kind)))


def integrator(functions: SystemFunctions, name: str, kind: str, times, options: dict,
               keep: bool = True, workspace: Workspace | None = None) -> NamedCall:
    """IDAS on the DAE from tau = 0 over `times` (relative to the start) with `options`: the
    one kept for the same grid and options, else a new one (kept unless keep is False: a
    restart within a run, an event's trial points). Called by input names, its outputs
    written into NumPy (runtime.buffers.NamedCall)."""
    grid = tuple(float(t) for t in times)

    def build() -> NamedCall:
        return NamedCall(ca.integrator("dynamics", "idas", problem(functions, name, kind,
                                                                   workspace),
                                       0.0, list(grid), options))

    if not keep:
        return build()
    return of(functions, workspace).kept("dae_integrators",
                                         (name, kind, grid, _frozen(options)), build)


def _frozen(options: dict) -> tuple:
    """The options as a hashable key (vectors as tuples of floats)."""
    def value(v):
        return tuple(float(x) for x in v) if isinstance(v, (list, tuple, np.ndarray)) else v

    return tuple(sorted((key, value(v)) for key, v in options.items()))
