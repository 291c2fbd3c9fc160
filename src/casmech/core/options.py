"""The options of each analysis type: one frozen dataclass per type, every default written here
once, every field documented (docs/analyses.md#options lists them; a test keeps it current).

In YAML, the fields beside `solver` are keys of the `analysis:` block (formulation,
stabilization, method, at, inputs: docs/format.md); the others are under `analysis: {solver:
...}`, named as SUNDIALS and Adams users know them where there is such a name (max_steps,
max_step, initial_step). The command line sets any of them by `casmech run --option
KEY=VALUE` (a key under `solver:` may leave out `solver.`), the API by `casmech.analyze(...,
options=...)` (a dataclass below or a mapping of keys); casmech.core.option_values checks the
values (unknown key with a did-you-mean, wrong type, out of range).

Sizes that only bound memory or batch work stay constants of their modules (the entries kept
per workspace, the columns per mapped call, the inner map of the prescribed step).
"""

from __future__ import annotations

from casmech.core.option_values import nested, option
from casmech.core.records import record
from casmech.core.registry import Names

# the registered formulations and auto: formulations.registry keeps it current
FORMULATIONS = Names(("rp", "romega", "joint", "auto"))
STABILIZATIONS = ("ggl", "projection")
METHODS = ("auto", "adams", "bdf", "dop853")
LOOP_ROWS = ("integrator", "solved")


def _formulation():
    return option("auto", "the equations of motion: auto (joint coordinates, rp after a loop run "
                  "that failed or passed a singular pose, or with a floating body in a loop), "
                  "joint, rp (r-p DAE), romega (Newton-Euler DAE); docs/formulations.md",
                  choices=FORMULATIONS)


def _stabilization():
    return option("ggl", "how the r-p and r-omega DAEs keep the constraints: ggl (the "
                  "stabilized index-2 DAE) or projection (the index-1 DAE projected back when it "
                  "drifts); asking for it with formulation auto runs rp",
                  choices=STABILIZATIONS)


def _method():
    return option("auto", "the method for joint coordinates on a tree: CVODES's adams or bdf, "
                  "dop853 (an explicit Runge-Kutta pair of order 8; with loops, their ODE "
                  "projected onto the loops after each step), or auto (bdf when the ODE is "
                  "stiff at t0: solver.stiff_threshold; adams where contacts or stops cap the "
                  "step or where dop853 would not run in C: an interpreted model, a tree of "
                  "more than compile.mapped_bodies bodies, no C compiler; else dop853; loops: "
                  "dop853 on a compiled model without force elements or capped steps, else "
                  "IDAS)",
                  choices=METHODS)


@record
class LinearAlgebra:
    """Sizes (entries, rows x columns) up to which LAPACK's dense routines are used instead of
    casmech's sparse QR (numerics.numeric_qr, equations.checks), and the rank cuts. The dense
    and sparse answers agree to roundoff; the sizes trade speed against memory."""

    dense_entries: int = option(20_000, "least squares (Newton steps, velocities) by NumPy's SVD "
                                "up to this many entries", low=0)
    dense_qr_entries: int = option(500_000, "LAPACK's QR up to this many entries: least squares "
                                   "of a full-rank matrix, the rank scan of the constraint rows",
                                   low=0)
    dense_norm_entries: int = option(20_000, "the 2-norm of a matrix by a dense SVD up to this "
                                     "many entries, else by power iteration", low=0)
    dense_svd_entries: int = option(250_000, "the joints a dependency involves (failure "
                                    "messages) by a dense SVD up to this many entries", low=0)
    full_rank: float = option(1e-12, "a QR factor whose min |R_kk| / max |R_kk| exceeds this "
                              "is taken as full rank", low=0, high=1, open_low=True)
    rank_tolerance: float = option(1e-9, "a constraint row within this times max(|Phi_q|_2, 1) "
                                   "of the span of the rows before it is redundant (DOF, rank, "
                                   "the rows the DAEs mask)", low=0, high=1, open_low=True)


@record
class Assembly:
    """Newton's method on the position constraints: the assembly every analysis starts from,
    the rows kinematics does one by one, the projections of dynamics (runtime.assembly)."""

    tolerance: float = option(1e-12, "max |Phi| at convergence (also the mapped kinematics rows' "
                              "test)", unit="m or 1", low=0, high=1e-3, open_low=True)
    max_iterations: int = option(50, "Newton iterations before the assembly fails (and the "
                                 "projections' iterations)", low=1, high=100_000)
    max_driver_step: float = option(0.5, "driver continuation: drivers of composite joints are "
                                    "reached from the file's pose in steps of at most this",
                                    unit="rad or m", low=0, open_low=True)
    continuation_tolerance: float = option(1e-8, "max |Phi| at which an intermediate "
                                           "continuation step is taken as converged",
                                           low=0, high=1, open_low=True)
    root_tolerance: float = option(1e-14, "max |KKT residual| of the closest-point "
                                   "rootfinder's Newton (numerics.kkt)", low=0, high=1e-3,
                                   open_low=True)
    root_iterations: int = option(20, "the closest-point rootfinder's Newton iterations from "
                                  "the least-squares start (2-4 are typical)", low=1,
                                  high=1000)
    linear_algebra: LinearAlgebra = nested(LinearAlgebra, "dense or sparse linear algebra")


@record
class Fallback:
    """The augmented-Lagrangian ODE integrated by projected Runge-Kutta steps, which r-p and
    r-omega dynamics fall back to where IDAS fails at a singular pose (formulations.augmented,
    runtime.projected_rk4)."""

    penalty: float = option(1e8, "the penalty a, relative to max(diag M) (and to "
                            "max(diag P^T P) with row scaling)", low=0, open_low=True)
    iterations: int = option(6, "augmented-Lagrangian iterations per acceleration solve",
                             low=1, high=1000)
    projection_iterations: int = option(2, "Gauss-Newton steps per call of the projection onto "
                                        "the constraints", low=1, high=1000)
    safety: float = option(0.5, "the weighted error estimate step doubling aims at (1: the "
                           "tolerance)", low=0, high=1, open_low=True)
    max_steps: int = option(50_000, "fine Runge-Kutta steps per output interval before the "
                            "fallback fails", low=2)
    always: bool = option(False, "integrate the augmented-Lagrangian ODE from t0 instead of the "
                          "DAE (to compare the two)")


@record
class JointCompile:
    """How much of the joint formulation a compiled bundle compiles too (runtime.joint_dynamics;
    an interpreted bundle compiles nothing, a parametric library holds its own)."""

    ode_bodies: int = option(128, "the tree's ODE or the loops' DAE compiled up to this many "
                             "bodies (above: interpreted)", low=0)
    motion_bodies: int = option(32, "the results rows' function compiled up to this many bodies",
                                low=0)
    quick_build_instructions: int = option(30_000, "an ODE of more SX instructions is built at "
                                           "-O0 unless $CASMECH_CFLAGS is set", low=0)
    mapped_bodies: int = option(128, "a tree of more bodies (no loops, drivers or force elements) "
                                "not compiled whole runs as per-joint kernels, compiled once "
                                "for every model", low=0)


@record
class DynamicsSolver:
    """The integrators of dynamics: SUNDIALS IDAS (r-p, r-omega, loops in joint coordinates)
    and CVODES (trees), and what surrounds them."""

    max_steps: int = option(50_000, "integrator steps per output interval before it gives up "
                            "(SUNDIALS' mxstep)", low=1)
    max_step: float | None = option(None, "the largest integrator step (SUNDIALS' hmax, Adams' "
                                    "HMAX); none: SUNDIALS' own; contact and stops cap it at "
                                    "the output step too", unit="s", low=0, open_low=True)
    initial_step: float | None = option(None, "the first integrator step (SUNDIALS' h0, Adams' "
                                        "HINIT); none: the integrator's own, for the index-2 "
                                        "DAEs where an order-1 step's error is a quarter of "
                                        "the tolerance", unit="s", low=0, open_low=True)
    chunk: int = option(256, "output intervals per IDAS call of the r-p and r-omega DAEs when "
                        "rows are wanted as they come (a progress bar, a stop event) or after a "
                        "failure, doubling from call to call (IDAS restarts between calls); "
                        "otherwise ggl integrates the whole grid in one call", low=1)
    joint_chunk: int = option(1000, "output intervals per CVODES or IDAS call in joint "
                              "coordinates", low=1)
    ggl_failures: int = option(3, "chunks the index-2 DAE may fail on before the index-1 DAE "
                               "integrates the rest", low=0)
    drift_tolerance: float = option(1e-9, "stabilization projection: max |Phi| before the state "
                                    "is projected back (at least 100 atol)", unit="m or 1",
                                    low=0, open_low=True)
    algebraic_tolerance: float = option(1e-8, "the least absolute tolerance of the index-2 DAEs' "
                                        "accelerations and multipliers in IDAS's Newton test "
                                        "(they are out of its error test)", low=0,
                                        open_low=True)
    mu_tolerance: float = option(1.0, "the absolute tolerance of the index-2 DAEs' multiplier "
                                 "mu in IDAS's Newton test", low=0, open_low=True)
    stiff_threshold: float = option(10.0, "method auto: bdf when the ODE's fastest eigenvalue at "
                                    "t0 times the output step exceeds this", low=0,
                                    open_low=True)
    stiff_states: int = option(200, "method auto examines ODEs of up to this many states (a "
                               "dense eigenproblem); larger ones are not examined", low=0)
    singular_pose_ratio: float = option(1e-3, "a run with loops passed near a singular pose "
                                        "where the Gram determinant of its unit constraint rows "
                                        "falls below this times its value at t0", low=0,
                                        high=1, open_low=True)
    event_iterations: int = option(100, "Illinois steps locating one event crossing", low=1)
    loop_rows: str = option("solved", "the loop closures' multipliers of a joint-coordinate "
                            "run's results rows: solved (the saddle system solved at each row's "
                            "state: reactions as accurate as the state) or integrator (IDAS's "
                            "algebraic states at the row, interpolated over its step and out of "
                            "its error test); docs/formulations.md", choices=LOOP_ROWS)
    min_closing_speed: float = option(1.0, "the least closing speed a sphere pair's step cap "
                                      "assumes (docs/forces.md#contact)", unit="m/s", low=0,
                                      open_low=True)
    fallback: Fallback = nested(Fallback, "the singular-pose fallback of rp and romega")
    compile: JointCompile = nested(JointCompile, "joint coordinates in a compiled bundle")
    assembly: Assembly = nested(Assembly, "the initial assembly and the projections")


@record
class DynamicsOptions:
    """analysis type dynamics (runtime.dynamics, runtime.joint_dynamics)."""

    formulation: str = _formulation()
    stabilization: str = _stabilization()
    method: str = _method()
    solver: DynamicsSolver = nested(DynamicsSolver, "the integrators")


@record
class KinematicsSolver:
    """The prescribed motion over the output grid (runtime.kinematics)."""

    pivot_ratio: float = option(1e-10, "a row whose Phi_q has min |R_kk| / max |R_kk| below "
                                "this is done by the per-row code, which tells a singular "
                                "configuration", low=0, high=1)
    min_block: int = option(16, "rows of the first mapped call after a row the per-row code "
                            "did", low=1)
    max_block: int = option(2048, "most rows per mapped call (fewer when a call would take "
                            "longer than the cancellation poll allows)", low=1)
    assembly: Assembly = nested(Assembly, "the assembly at t0 and the per-row Newton")


@record
class KinematicsOptions:
    """analysis type kinematics."""

    solver: KinematicsSolver = nested(KinematicsSolver, "the prescribed motion")


@record
class InverseDynamicsOptions(KinematicsOptions):
    """analysis type inverse_dynamics: the kinematics rows read as the forces that drive them."""


@record
class StaticsSolver:
    """Pseudo-transient continuation to the equilibrium (runtime.statics)."""

    max_iterations: int = option(200, "steps before statics reports no equilibrium", low=1)
    force_tolerance: float = option(1e-10, "|R|_inf at convergence, relative to the largest "
                                    "applied load", low=0, high=1, open_low=True)
    max_rotation: float = option(0.5, "the most a body may turn in one step", unit="rad",
                                 low=0, open_low=True)
    trust_bisections: int = option(8, "halvings of log(mu) bracketing the step that turns a "
                                   "body max_rotation", low=0, high=100)
    growth: float = option(0.5, "the pseudo time step grows by at least 1/growth after a step "
                           "that lowered the residual", low=0, high=1, open_low=True)
    max_escapes: int = option(3, "departures from unstable equilibria along their most unstable "
                              "mode", low=0)
    escape_rotation: float = option(0.1, "how far a departure moves (radians, or this fraction "
                                    "of the model's size)", low=0, open_low=True)
    zero_omega2: float = option(1e-12, "squared frequencies below the larger of this and "
                                "neutral_ratio times the largest count as zero", unit="1/s^2",
                                low=0, open_low=True)
    neutral_ratio: float = option(1e-10, "see zero_omega2", low=0, high=1)
    polish_steps: int = option(3, "Newton steps past the tolerance, each kept while it lowers "
                               "the residual", low=0, high=100)
    assembly: Assembly = nested(Assembly, "the assembly and each step's projection")


@record
class StaticsOptions:
    """analysis type statics."""

    solver: StaticsSolver = nested(StaticsSolver, "the equilibrium")


@record
class ModalSolver:
    """Modes at the equilibrium (statics) or at a time of a dynamics run."""

    real_cut: float = option(1e-9, "an eigenvalue with |Im s| <= this times |s| is real",
                             low=0, high=1)
    statics: StaticsSolver = nested(StaticsSolver, "the equilibrium (no `at`)")
    dynamics: DynamicsSolver = nested(DynamicsSolver, "the dynamics run to `at`")


@record
class ModalOptions:
    """analysis type modal (runtime.modal)."""

    at: float | None = option(None, "linearize at this time of a dynamics run (0 <= at <= "
                              "t_end); none: at the static equilibrium", unit="s", low=0)
    inputs: tuple[str, ...] | None = option(None, "the effort-motor joints and force elements "
                                            "whose force is an input; none: every effort motor")
    formulation: str = _formulation()
    stabilization: str = _stabilization()
    method: str = _method()
    solver: ModalSolver = nested(ModalSolver, "the equilibrium or the run, and the modes")

    def dynamics(self) -> DynamicsOptions:
        """The options of the dynamics run to `at`."""
        return DynamicsOptions(self.formulation, self.stabilization, self.method,
                               self.solver.dynamics)


@record
class AssemblySolver:
    """The assembly analysis: one state at t0."""

    assembly: Assembly = nested(Assembly, "Newton on the position constraints")


@record
class AssemblyOptions:
    """analysis type assembly."""

    solver: AssemblySolver = nested(AssemblySolver, "the assembly")


# analysis type -> its options (in the order docs/format.md lists the types)
OPTIONS: dict[str, type] = {
    "kinematics": KinematicsOptions,
    "dynamics": DynamicsOptions,
    "inverse_dynamics": InverseDynamicsOptions,
    "statics": StaticsOptions,
    "assembly": AssemblyOptions,
    "modal": ModalOptions,
}
AnalysisOptions = (DynamicsOptions | KinematicsOptions | StaticsOptions | ModalOptions
                   | AssemblyOptions)


def assembly_of(options) -> Assembly:
    """The assembly settings any analysis's options hold (modal: those of the run it makes)."""
    solver = options.solver
    if isinstance(options, ModalOptions):
        return solver.statics.assembly if options.at is None else solver.dynamics.assembly
    return solver.assembly
