"""A Workspace: what analyses derive from one bundle of system functions and reuse in later
runs (integrators, the spanning tree and joint system, consistent starts, mapped row
functions), so that a run repeated on the same bundle builds none of it again.

The bundle (equations.functions.SystemFunctions) is immutable; the workspace is owned by the
caller of the analyses: `casmech.analyze(functions, workspace=...)`, or by default the one
`default(functions)` keeps for the bundle while it lives (a weak association: the workspace
goes with the bundle). Each kind of entry is bounded (KINDS: the entries kept, the oldest
dropped first) and keyed by what it depends on besides the bundle (a start, an output grid,
the option values it was built with), so runs with other options never reuse a stale entry.
Entries never hold the bundle itself. What they hold is not shared between threads: DOP853's
and the rows' C loops write one set of work vectors, solver instances one memory, so analyses on
one workspace run one at a time (`lock`, held by runtime.analyses.analyze; other bundles' and
other workspaces' runs go on beside them).
"""

from __future__ import annotations

import threading
import weakref
from collections.abc import Callable, Hashable
from typing import TypeVar

from casmech.equations.functions import SystemFunctions
from casmech.errors import UsageError
from casmech.runtime.memo import kept

T = TypeVar("T")

# kind of entry -> the most entries kept (what each is: the module that builds it)
KINDS: dict[str, int] = {
    "analysis_plans": 16,  # what analyze derives from its arguments (runtime.analyses._Plan)
    "analysis_settings": 16,  # checked settings, by analyze's arguments (runtime.analyses)
    "column_names": 1,  # the results table's column names (runtime.results)
    "frictions": 1,  # whether dynamics switches frictions' modes, amends driven ones' loads
    "spanning_tree": 1,  # formulations.tree.spanning_tree (runtime.joint_dynamics)
    "joint_system": 4,  # the joint formulation's functions, by the compile options
    "joint_starts": 8,  # joint coordinates' initial states, by t0 and assembly options
    "stiffness": 8,  # method auto's spectral radius of the tree's ODE, by start
    "cvodes": 8,  # CVODES instances, by grid and integrator options
    "dop853": 4,  # runtime.dop853 integrators of a tree's ODE, by integrator options
    "dop853_in_c": 4,  # whether DOP853 over a joint system runs in C (method auto's choice)
    "idas": 8,  # joint coordinates' IDAS instances, also by start
    "joint_least_norm": 8,  # least-norm multipliers of masked loop rows, by mask
    "joint_loop_rows": 8,  # loop rows' solved multipliers (runtime.joint_rows), by mask
    "loop_ode": 8,  # the loops' ODE and projection (runtime.projected_loops), by mask
    "joint_motion_maps": 16,  # results rows' column calls, by motion function
    "formulation_systems": 4,  # a formulation's System (runtime.formulation_run.generic)
    "dae_problems": 4,  # r-p / r-omega DAEs as casadi.integrator takes them
    "dae_integrators": 4,  # their IDAS instances (each holds its memory and Newton matrix)
    "dae_starts": 16,  # masks and consistent starts (runtime.dynamics)
    "dae_saddle": 2,  # the consistent start's saddle solve, per formulation
    "dae_rows": 8,  # results rows and drift checks, per formulation and mask
    "dae_row_maps": 16,  # their column calls
    "closest_point": 4,  # assembly's closest-point rootfinder, by independent rows
    "saddle": 4,  # accelerations' saddle solve, by rows
    "projection": 4,  # the projection onto the constraints, by formulation and options
    "prescribed_grids": 16,  # kinematics' mapped grids, by padded block length
    "results_row": 1,  # the results table's row function (runtime.results)
    "singular_pose_jacobian": 1,  # dense Phi_q at output rows (runtime.singular_poses)
    "statics_tangent": 1,  # statics' residual, tangent and mass (runtime.statics)
    "sx_bundle": 1,  # an SX rebuild of a compiled bundle (runtime.linearize)
    "controlled": 2,  # bundles driven by a Python controller, by controls and controller
    "events": 1,  # the model's `events:` as Functions (runtime.events)
    "dof": 1,  # degrees of freedom at the file's pose (casmech.api.CompiledModel.dof)
    "joint_space": 1,  # the joint-space dynamics (casmech.api.joint_space)
    "readings": 1,  # the joint states and `outputs:` columns (runtime.results)
    "initial_holds": 1,  # the bundles holding the joints' `initial:` values (runtime.initial_holds)
}


class Workspace:
    """The entries analyses keep for one bundle (module docstring). `functions`: the bundle it
    serves; analyses refuse it for another."""

    def __init__(self, functions=None):
        self._bundle = None if functions is None else weakref.ref(functions)
        self._stores: dict[str, dict] = {}
        self.lock = threading.RLock()  # held by a run (module docstring)

    def serve(self, functions) -> Workspace:
        """This workspace, bound to `functions` on first use; a UsageError if it serves
        another bundle."""
        if self._bundle is None:
            self._bundle = weakref.ref(functions)
        elif self._bundle() is not functions:
            raise UsageError("this workspace holds the run data of another bundle of system "
                             "functions; make one per bundle (casmech.runtime.workspace."
                             "Workspace(functions))")
        return self

    def kept(self, kind: str, key: Hashable, build: Callable[[], T]) -> T:
        """The entry of `kind` under `key`, built by build() when missing (at KINDS[kind]
        entries, the oldest goes first)."""
        store = self._stores.get(kind)
        return kept(self.store(kind) if store is None else store, key, build, KINDS[kind])

    def one(self, kind: str, build: Callable[[], T]) -> T:
        """The one entry of `kind`, built by build() when missing."""
        return self.kept(kind, None, build)

    def store(self, kind: str) -> dict:
        """The entries of `kind` (for code that keeps them itself, bounded by KINDS)."""
        if kind not in KINDS:
            raise KeyError(f"no workspace entry kind {kind!r}")
        return self._stores.setdefault(kind, {})

    def drop(self, kind: str | None = None) -> None:
        """Forget the entries of `kind`, or all of them; analyze's plans go with any kind
        (a plan holds entries of the others)."""
        if kind is None:
            self._stores.clear()
        else:
            self._stores.pop(kind, None)
            self._stores.pop("analysis_plans", None)

    def __len__(self) -> int:
        return sum(len(store) for store in self._stores.values())


_defaults: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_making = threading.Lock()


def default(functions) -> Workspace:
    """The workspace analyses use for `functions` when their caller gives none: one per
    bundle, for as long as the bundle lives. Anything but a bundle is a UsageError: a
    ResolvedModel (casmech.load's) still needs casmech.compile."""
    if not isinstance(functions, SystemFunctions):
        loaded = type(functions).__name__ == "ResolvedModel"
        raise UsageError(
            f"analyses take a model's system functions, not {type(functions).__name__}"
            + ("; compile the loaded model first: casmech.analyze(casmech.compile(model))"
               if loaded else "; casmech.compile(casmech.load(path)) gives them"))
    found = _defaults.get(functions)
    if found is None:
        with _making:  # one default per bundle, whichever thread asks first
            found = _defaults.get(functions)
            if found is None:
                found = _defaults[functions] = Workspace(functions)
    return found


def of(functions, workspace: Workspace | None) -> Workspace:
    """`workspace` (checked to serve `functions`), or the bundle's default one."""
    return default(functions) if workspace is None else workspace.serve(functions)
