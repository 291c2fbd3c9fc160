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
- `method: dop853` asked for makes auto run joint coordinates wherever they apply (loops
  without a floating body: in a compiled bundle whose joint system stays interpreted, or in a
  run too long to be examined, too); the rp run after a loop run that failed or passed a
  singular pose stays. A method of joint coordinates (adams, dop853: schema.limits.
  JOINT_METHODS) asked for on loops with a floating body cannot run: `method_problem` says
  why, and runtime.analyses' analysis_settings raises it as E409 at the method (located when
  the file wrote it) before anything runs. A method of a tree alone (not in schema.limits.
  LOOP_METHODS: adams) asked for on loops (or couplings) under auto or joint is E409 too:
  their joint DAE goes to IDAS, whose only method is BDF.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from casmech.core.options import DynamicsSolver
from casmech.equations.functions import SystemFunctions
from casmech.errors import AnalysisError, FailureContext, Interrupted
from casmech.formulations.registry import FORMULATIONS
from casmech.formulations.tree import Tree
from casmech.runtime.joint_dynamics import lags_bundle
from casmech.runtime.results import Result
from casmech.runtime.workspace import Workspace
from casmech.schema.limits import BDF, JOINT_METHODS, LOOP_METHODS, joint_method

DEFAULT = DynamicsSolver()  # the defaults (core.options)


def choice(tree: Tree, formulation: str, examinable: Callable[[], bool],
           lags: Callable[[], bool], method: str = "auto") -> str:
    """The formulation to run first: "joint" or the one asked for (rp, romega, another
    registered one); examinable(): whether the run's rows can be examined for singular poses;
    lags(): lags_bundle. Both are asked only for loops in auto without a method of joint
    coordinates (a tree's choice needs neither; module docstring)."""
    if formulation != "auto" and tree.couplings and \
            not FORMULATIONS[formulation].takes_couplings:
        taking = [name for name, entry in FORMULATIONS.items() if entry.takes_couplings]
        raise AnalysisError(FailureContext(
            None, f"the {formulation} formulation does not take couplings of joint "
            f"coordinates; write formulation: {', '.join(taking)} or auto",
            [(j.name, j.source, 0.0) for j in tree.couplings], "coupling"))
    if formulation != "auto":
        return formulation
    if tree.is_tree or (not tree.floating_loops and method == "dop853"):
        return "joint"
    return "joint" if not tree.floating_loops and examinable() and not lags() else "rp"


def method_problem(tree: Callable[[], Tree], formulation: str, method: str,
                   bodies: Sequence[str] = ()) -> tuple[str, str] | None:
    """(why, hint) when `method` does not run under `formulation`: a method of joint
    coordinates (JOINT_METHODS) with a formulation other than joint or auto, with auto on a
    model with loops and a floating body (choice: rp; `bodies`: the body names by index), or
    one of a tree alone (not LOOP_METHODS) on a model with loops; None otherwise. tree() is
    asked only for joint or auto with such a method."""
    if method not in JOINT_METHODS:
        return None
    if formulation in ("rp", "romega"):
        return (f"{joint_method(method)}; the rp and romega DAEs are integrated by {BDF}",
                "write formulation: joint (or auto), or remove method")
    if formulation not in ("auto", "joint"):
        return (f"{joint_method(method)}; the {formulation} formulation integrates its own "
                "equations by CVODES or IDAS", "write formulation: joint, or remove method")
    found = tree()
    if formulation == "auto" and found.floating_loops:
        child = next(joint.child for joint in found.joints if joint.joint is None)
        body = f"body '{bodies[child]}'" if child < len(bodies) else "a body"
        return (f"{joint_method(method)}; formulation auto runs this model in rp, integrated "
                f"by {BDF}: it has loops and {body} floats in the spanning tree (no tree joint "
                "reaches it from ground, so its joint coordinates would be its r-p ones plus "
                "the recursion's overhead)",
                "remove method (auto) or write method: bdf; formulation: joint runs joint "
                "coordinates with the floating body's free joint, slower than rp "
                "(docs/formulations.md)")
    if found.is_tree or method in LOOP_METHODS:
        return None
    closing = "loops or couplings" if found.couplings else "loops"
    return (f"{joint_method(method)}; this model has {closing}, whose DAE in joint "
            f"coordinates is integrated by {BDF}",
            f"write method: {' or '.join(LOOP_METHODS)} (the loops' ODE, projected onto "
            "them after each step) or bdf, or remove method (auto)")


def first_of(functions: SystemFunctions, tree: Tree, formulation: str, rows: int,
             settings: DynamicsSolver = DEFAULT, workspace: Workspace | None = None,
             method: str = "auto") -> str:
    """`choice` for a run of `rows` output rows of `functions` (the arguments as run takes
    them); a function of these alone, so a caller running the same run again may keep it."""
    def examinable() -> bool:
        from casmech.runtime.singular_poses import examinable

        return examinable(functions, rows, workspace)

    return choice(tree, formulation, examinable,
                  lambda: lags_bundle(functions, settings.compile), method)


def run(functions: SystemFunctions, tree: Tree, formulation: str, rows: int,
        joint: Callable[[], Result], other: Callable[[str], Result],
        settings: DynamicsSolver = DEFAULT,
        workspace: Workspace | None = None, method: str = "auto",
        first: str | None = None) -> Result:
    """Run `joint()` or `other(formulation)` as `choice` says (rows: the run's output rows;
    method: the run's; `first`: first_of's answer where the caller kept it);
    with loops in auto, the rp run after a joint run that failed or passed a singular pose.
    Singular poses are recorded in the metadata of a run with loops."""
    if first is None:
        first = first_of(functions, tree, formulation, rows, settings, workspace, method)
    loops = not tree.is_tree

    def examined(result: Result) -> Result:
        """`result` with the singular poses of a run with loops in its metadata."""
        from casmech.runtime.singular_poses import singular_poses

        poses = singular_poses(functions, result, loops, settings, workspace)
        if poses is not None:
            result.metadata["singular_poses"] = poses
        return result

    fallback = formulation == "auto" and first == "joint" and loops
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
        if not loops:  # a tree's run: nothing to examine (singular_poses)
            return result
        poses = examined(result).metadata.get("singular_poses")
        if not (fallback and poses):
            return result
        from casmech.runtime.singular_poses import describe

        why = f"joint coordinates went {describe(poses[0])}"
    result = examined(other("rp"))
    result.metadata["formulation_fallback"] = why
    return result
