"""`formulation: auto` for a dynamics run: which formulation runs, and the loops' fallback.

- A tree: joint coordinates (an ODE on CVODES).
- Loops whose spanning tree reaches every body through the file's joints (no `free` joint),
  in a run whose rows can be examined (singular_poses.MAX_ENTRIES): joint coordinates (the
  tree's ODE and the cut joints' rows: a small DAE on IDAS). After the run the rows are
  examined for singular poses (runtime.singular_poses); a run that failed or passed one is
  run again in `rp`, whose augmented-Lagrangian fallback is built for them (the joint DAE can
  pass a flat pose of a four-bar without failing, off the exact motion: docs/formulations.md),
  and `metadata.formulation_fallback` says why.
- Loops with a floating body in the tree (held only by basic or composite constraints, all
  cut): `rp`; the tree coordinates are then the body's own plus the recursion's overhead.
  Loops in a compiled bundle whose joint system stays interpreted (joint_dynamics.lags_bundle:
  above solver.compile.ode_bodies, or a parametric library built without the joint functions):
  `rp`, compiled. (Measurements: docs/decisions/formulation-auto.md.) A compiled parametric
  bundle's joint system is compiled in its library (codegen.parametric), so its loops run joint
  coordinates.
- Couplings of joint coordinates (gear, rack_pinion, coupler: rows over the bodies of
  several joints) are loop-closure rows of the joint DAE (formulations/joint_system.py), so a
  coupled mechanism is a mechanism with loops above: joint coordinates unless a body floats
  in the tree (a screw's nut); why: docs/decisions/formulation-auto.md. A registered
  formulation whose takes_couplings is False asked for is an error naming them.
- A DAE stabilization asked for makes the formulation `rp` before this module is reached
  (api.analysis_settings, the one place that rule lives).
"""

from __future__ import annotations

from collections.abc import Callable

from casmech.core.options import DynamicsSolver
from casmech.equations.functions import SystemFunctions
from casmech.errors import AnalysisError, FailureContext, Interrupted
from casmech.formulations.registry import FORMULATIONS
from casmech.formulations.tree import Tree
from casmech.runtime.joint_dynamics import lags_bundle
from casmech.runtime.results import Result
from casmech.runtime.singular_poses import describe, examinable, singular_poses
from casmech.runtime.workspace import Workspace

DEFAULT = DynamicsSolver()  # the defaults (core.options)


def choice(tree: Tree, formulation: str, examinable: Callable[[], bool],
           lags: Callable[[], bool]) -> str:
    """The formulation to run first: "joint" or the one asked for (rp, romega, another
    registered one); examinable(): whether the run's rows can be examined for singular poses;
    lags(): lags_bundle. Both are asked only for loops in auto (a tree's choice needs
    neither)."""
    if tree.couplings and formulation != "auto" and \
            not FORMULATIONS[formulation].takes_couplings:
        taking = [name for name, entry in FORMULATIONS.items() if entry.takes_couplings]
        raise AnalysisError(FailureContext(
            None, f"the {formulation} formulation does not take couplings of joint "
            f"coordinates; write formulation: {', '.join(taking)} or auto",
            [(j.name, j.source, 0.0) for j in tree.couplings], "coupling"))
    if formulation != "auto":
        return formulation
    return "joint" if tree.is_tree or (not tree.floating_loops and examinable() and not lags()) \
        else "rp"


def run(functions: SystemFunctions, tree: Tree, formulation: str, rows: int,
        joint: Callable[[], Result], other: Callable[[str], Result],
        settings: DynamicsSolver = DEFAULT,
        workspace: Workspace | None = None) -> Result:
    """Run `joint()` or `other(formulation)` as `choice` says (rows: the run's output rows);
    with loops in auto, the rp run after a joint run that failed or passed a singular pose.
    Singular poses are recorded in the metadata of a run with loops."""
    first = choice(tree, formulation, lambda: examinable(functions, rows),
                   lambda: lags_bundle(functions, settings.compile))

    def examined(result: Result) -> Result:
        """`result` with the singular poses of a run with loops in its metadata."""
        poses = singular_poses(functions, result, not tree.is_tree, settings, workspace)
        if poses is not None:
            result.metadata["singular_poses"] = poses
        return result

    fallback = formulation == "auto" and first == "joint" and not tree.is_tree
    if first != "joint":
        return examined(other(first))
    try:
        result = joint()
    except Interrupted:
        raise
    except AnalysisError as error:
        if not fallback:
            raise
        why = f"the joint DAE failed ({str(error).splitlines()[0]})"
    else:
        poses = examined(result).metadata.get("singular_poses")
        if not (fallback and poses):
            return result
        why = f"joint coordinates went {describe(poses[0])}"
    result = examined(other("rp"))
    result.metadata["formulation_fallback"] = why
    return result
