"""Linearization and modes at the static equilibrium (runtime.statics), or with `analysis:
{at: t}` at that time of a dynamics run (linearize_at: runtime.linearize, the same chart and
state, A and B by AD through the chart's ODE, velocity terms included).

Independent coordinates: z with q = q* + N z, N the orthonormal null-space basis of Phi_q(q*)
from a column-pivoted QR of Phi_q^T (statics.null_space; Euler-parameter normalization rows
included, so z never changes a quaternion's norm). Projecting M q_ddot + Phi_q^T lam = Q on N
removes the multipliers; to first order about the equilibrium (where Q - Phi_q^T lam* = 0)

    M_r z'' + C_r z' + K_r z = 0,   M_r = N^T M N,  C_r = -N^T dQ/dq_dot N,
    K_r = -N^T d(Q - Phi_q^T lam*)/dq N   (lam* fixed: the constraint-curvature term),

all derivatives by CasADi's AD (statics.tangent_function). State x = [z; z'],
A = [[0, I], [-M_r^-1 K_r, -M_r^-1 C_r]]. Inputs u: a torque or force added to each effort
motor (`<joint>.torque` / `<joint>.force`), or the effort-motor joints and force elements
`analysis: {inputs: [...]}` names (runtime.linearize.INPUT_KINDS), B = [0; M_r^-1 N^T G] with
G their generalized forces per unit input. Outputs y = C x (D = 0): every
body's translation and small global rotation (2 E(p) dp) away from q*:
`<body>.dx .dy .dz .rx .ry .rz`.

Modes: the eigenvalues s of A, a complex pair once (Im s > 0), a real eigenvalue (an
overdamped motion) on its own, a DOF of zero stiffness as one mode at s = 0;
frequency_hz = |s| / 2 pi (undamped natural frequency), damped_frequency_hz = |Im s| / 2 pi,
damping_ratio = -Re s / |s|; sorted by frequency. Mode shapes: the eigenvector's z mapped to
body motions (n_modes x n_bodies x 6), scaled so that the largest entry is 1.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import field, replace
from pathlib import Path

import numpy as np

from casmech.core.atomic import atomic
from casmech.core.options import ModalOptions, ModalSolver
from casmech.core.records import record
from casmech.equations.functions import SystemFunctions
from casmech.errors import AnalysisError, FailureContext, UsageError
from casmech.runtime import kinematics, labelled, statics
from casmech.runtime import linearize as linear
from casmech.runtime.results import Result
from casmech.runtime.workspace import Workspace
from casmech.schema.resolved import Analysis

MODE_COLUMNS = ("mode", "frequency_hz", "damping_ratio", "eigenvalue_real", "eigenvalue_imag",
                "damped_frequency_hz")
MOTION = ("dx", "dy", "dz", "rx", "ry", "rz")
# what a modal run writes beside results.csv (cli/run.py's ANALYSIS_FILES names them too,
# to remove an earlier run's without importing this module)
FILES = ("modes.csv", "linear_model.npz")
DEFAULT = ModalSolver()  # real_cut: |Im s| <= real_cut |s| is a real eigenvalue


@record(frozen=False)
class LinearModel:
    """x' = A x + B u, y = C x + D u about q (states z, z'): the static equilibrium or a state
    (t, q, q_dot) of a run; and its modes."""

    A: np.ndarray  # noqa: N815 (the usual names)
    B: np.ndarray  # noqa: N815
    C: np.ndarray  # noqa: N815
    D: np.ndarray  # noqa: N815
    state_names: list[str]
    input_names: list[str]
    output_names: list[str]
    q: np.ndarray  # the equilibrium
    basis: np.ndarray  # N: dq = N z
    eigenvalues: np.ndarray  # one per mode (complex)
    mode_shapes: np.ndarray  # (modes, bodies, 6) complex
    body_names: list[str] = field(default_factory=list)
    mode_vectors: np.ndarray | None = None  # (k, modes) complex: modes in z, scaled as shapes
    t: float | None = None  # the time of the run linearized at; None: the static equilibrium
    q_dot: np.ndarray | None = None  # the velocities there (zero at the equilibrium)

    @property
    def linearized_at(self) -> str:
        """'equilibrium' or 't = <time>' (metadata.json's `linearized_at`)."""
        return "equilibrium" if self.t is None else f"t = {self.t:.12g}"

    def state_space(self):
        """The linear model as a python-control StateSpace (states, inputs and outputs named,
        '.' written '_': python-control keeps '.' for subsystem names, so `pivot.torque` is
        `pivot_torque`); python-control is optional (`pip install 'casmech[control]'`)."""
        try:
            import control
        except ImportError:
            raise ImportError("LinearModel.state_space needs python-control: "
                              "pip install 'casmech[control]'") from None

        def names(labels):
            return [label.replace(".", "_") for label in labels]

        return control.ss(self.A, self.B, self.C, self.D, states=names(self.state_names),
                          inputs=names(self.input_names), outputs=names(self.output_names))

    @property
    def frequency_hz(self) -> np.ndarray:
        return np.abs(self.eigenvalues) / (2 * np.pi)

    @property
    def damped_frequency_hz(self) -> np.ndarray:
        return np.abs(self.eigenvalues.imag) / (2 * np.pi)

    @property
    def damping_ratio(self) -> np.ndarray:
        size = np.abs(self.eigenvalues)
        ratio = np.divide(-self.eigenvalues.real, size, out=np.zeros(size.shape), where=size > 0)
        return ratio + 0.0  # no -0.0

    def to_dataframes(self) -> dict:
        """{"A": ..., "B": ..., "C": ..., "D": ...} as pandas DataFrames labelled by the state,
        input and output names (runtime.labelled)."""
        return labelled.matrix_frames(self)

    def modes_dataframe(self):
        """The modes (modes.csv's table) as a DataFrame indexed by mode number."""
        return labelled.modes_frame(self)

    def mode_shapes_dataframe(self):
        """The mode shapes as a DataFrame: a row per mode, a column per `<body>.<motion>`."""
        return labelled.mode_shapes_frame(self, MOTION)

    def modes_table(self) -> tuple[list[str], np.ndarray]:
        values = np.column_stack([np.arange(1, len(self.eigenvalues) + 1), self.frequency_hz,
                                  self.damping_ratio, self.eigenvalues.real,
                                  self.eigenvalues.imag, self.damped_frequency_hz])
        return list(MODE_COLUMNS), values.reshape(-1, len(MODE_COLUMNS))

    def write_modes(self, path: Path) -> Path:
        """modes.csv: the table, mode numbers as integers, atomically."""
        names, values = self.modes_table()
        with atomic(Path(path), newline="") as handle:
            handle.write(",".join(names) + "\n")
            handle.writelines(",".join([str(int(row[0])), *map(repr, row[1:])]) + "\n"
                              for row in values.tolist())
        return Path(path)

    def write_npz(self, path: Path) -> Path:
        """linear_model.npz, atomically (core.atomic)."""
        path = Path(path)
        with atomic(path, "wb") as handle:
            np.savez(handle, A=self.A, B=self.B, C=self.C, D=self.D,
                     state_names=np.array(self.state_names, dtype=str),
                     input_names=np.array(self.input_names, dtype=str),
                     output_names=np.array(self.output_names, dtype=str),
                     q_equilibrium=self.q, q_dot=self.q_dot, linearized_at=self.linearized_at,
                     t=np.nan if self.t is None else self.t,
                     basis=self.basis, eigenvalues=self.eigenvalues,
                     mode_shapes=self.mode_shapes, mode_vectors=self.mode_vectors,
                     mode_shape_names=np.array(
                         [f"{b}.{m}" for b in self.body_names for m in MOTION], dtype=str))
        return path


def linearize(functions: SystemFunctions, system: statics.ReducedSystem,
              inputs: Sequence[str] | None = None, settings: ModalSolver = DEFAULT
              ) -> LinearModel:
    """The linear model and modes at an equilibrium's reduced system; `inputs`: the elements
    whose force is an input (runtime.linearize; None: every effort motor)."""
    k = system.dof
    stiffness = np.linalg.solve(system.mass, system.stiffness) if k else np.zeros((0, 0))
    damping = np.linalg.solve(system.mass, system.damping) if k else np.zeros((0, 0))
    a = np.block([[np.zeros((k, k)), np.eye(k)], [-stiffness, -damping]])
    names, forces = linear.input_forces(functions, inputs)
    n = system.q.size
    generalized = np.array(forces(0.0, system.q, np.zeros(n))).reshape(n, len(names))
    driven = np.linalg.solve(system.mass, system.basis.T @ generalized) if k else \
        np.zeros((0, len(names)))
    b = np.vstack([np.zeros((k, len(names))), driven])
    return _model(functions, system.q, system.basis, a, b, names, settings=settings)


def linearize_at(functions: SystemFunctions, t: float, q: np.ndarray, q_dot: np.ndarray,
                 inputs: Sequence[str] | None = None, settings: ModalSolver = DEFAULT,
                 workspace: Workspace | None = None) -> LinearModel:
    """The linear model and modes at a state (t, q, q_dot) of a run (runtime.linearize)."""
    phi_q = functions.matrix("phi_q", t, q)
    basis, rows = statics.basis_and_rows(phi_q, settings.statics)
    names, forces = linear.input_forces(functions, inputs)
    a, b = linear.state_space(functions, t, q, q_dot, basis, rows, forces, workspace)
    return _model(functions, q, basis, a, b, names, t, q_dot, settings)


def _model(functions: SystemFunctions, q: np.ndarray, basis: np.ndarray, a: np.ndarray,
           b: np.ndarray, names: list[str], t: float | None = None,
           q_dot: np.ndarray | None = None, settings: ModalSolver = DEFAULT) -> LinearModel:
    """The LinearModel of A, B at q (outputs: the body motions of N z; D = 0)."""
    k = basis.shape[1]
    outputs = statics.motion_map(q) @ basis
    c = np.hstack([outputs, np.zeros_like(outputs)])
    eigenvalues, shapes, vectors = _modes(functions, q, basis, a, settings)
    bodies = list(functions.body_names)
    return LinearModel(
        A=a, B=b, C=c, D=np.zeros((c.shape[0], len(names))),
        state_names=[f"z{i + 1}" for i in range(k)] + [f"z{i + 1}_dot" for i in range(k)],
        input_names=names, output_names=[f"{body}.{m}" for body in bodies for m in MOTION],
        q=q, basis=basis, eigenvalues=eigenvalues, mode_shapes=shapes,
        body_names=bodies, mode_vectors=vectors, t=t,
        q_dot=np.zeros_like(q) if q_dot is None else q_dot)


def _neutral(a: np.ndarray, settings: ModalSolver) -> tuple[np.ndarray, float]:
    """(the DOF of zero stiffness as orthonormal columns in z, the threshold of |omega^2|
    below which a frequency counts as 0): the eigenvectors of S = -A[k:, :k] (M_r^-1 K_r at an
    equilibrium) whose eigenvalues are 0 within statics.neutral_threshold."""
    k = a.shape[0] // 2
    values, vectors = np.linalg.eig(-a[k:, :k])
    threshold = statics.neutral_threshold(values.real, settings.statics)
    zero = np.abs(values) <= threshold
    if not zero.any():
        return np.zeros((k, 0)), threshold
    return np.linalg.qr(vectors[:, zero].real)[0], threshold


def _modes(functions: SystemFunctions, q: np.ndarray, basis: np.ndarray, a: np.ndarray,
           settings: ModalSolver):
    """(eigenvalues one per mode, sorted by |s|; mode shapes as body motions; the same modes
    in z, scaled alike: N z is the shape's motion of the coordinates). A DOF of zero
    stiffness is one mode at s = 0 shaped as its null vector of the stiffness block (A's
    eigenvalues there, a double zero or 0 and a real decay, are split by roundoff: |s| <=
    sqrt(neutral_threshold) counts as 0)."""
    k = basis.shape[1]
    if not k:
        return (np.zeros(0, complex), np.zeros((0, functions.n_bodies, 6), complex),
                np.zeros((0, 0), complex))
    neutral, threshold = _neutral(a, settings)
    values, vectors = np.linalg.eig(a)
    size = np.abs(values)
    real = np.abs(values.imag) <= settings.real_cut * np.maximum(size, 1e-300)
    keep = (real | (values.imag > 0)) & (size > np.sqrt(threshold))
    values, vectors = np.where(real, values.real, values)[keep], vectors[:k, keep]
    values = np.concatenate([np.zeros(neutral.shape[1]), values]).astype(complex)
    vectors = np.hstack([neutral, vectors]).astype(complex)
    order = np.lexsort((-values.real, np.abs(values)))
    vectors = vectors[:, order]
    motions = statics.motion_map(q) @ basis @ vectors
    shapes, scaled = [], []
    for motion, vector in zip(motions.T, vectors.T, strict=True):
        largest = motion[np.argmax(np.abs(motion))]
        scale = 1 / largest if abs(largest) > 0 else 1.0
        shapes.append((scale * motion).reshape(-1, 6))
        scaled.append(scale * vector)
    return (values[order], np.array(shapes).reshape(len(order), functions.n_bodies, 6),
            np.array(scaled).T.reshape(k, len(order)))


def run_modal(functions: SystemFunctions, settings: Analysis | None = None,
              progress=None, dynamics: Callable | None = None,
              workspace: Workspace | None = None) -> Result:
    """The modal analysis: at the static equilibrium (the default: its row, the linear model,
    the modes; a zero-stiffness DOF is kept as a zero-frequency mode, no equilibrium is an
    AnalysisError), or with `at` at that time of a dynamics run (its rows up to `at`, the
    linear model at the last). `settings`: the resolved `analysis:` block (its ModalOptions:
    `at`, `inputs`, the solvers; default the model's); `dynamics(functions, settings,
    progress)`: the dynamics run that reaches `at` (runtime.analyses)."""
    settings = functions.ir.analysis if settings is None else settings
    if not isinstance(settings.options, ModalOptions):  # the model's block of another type
        settings = replace(settings, options=ModalOptions())
    at, inputs, solver = settings.options.at, settings.options.inputs, settings.options.solver
    if at is None:
        equilibrium = statics.solve(functions, 0.0, settings=solver.statics,
                                    workspace=workspace)
        result = statics.equilibrium_result(functions, 0.0, equilibrium, "modal", progress)
        model = linearize(functions, equilibrium.system, inputs, solver)
    else:
        result = _run_to(functions, settings, float(at), progress, dynamics, workspace)
        model = linearize_at(functions, result.times[-1], result.q[-1], result.q_dot[-1], inputs,
                             solver, workspace)
    result.linear_model = model
    result.files = {FILES[0]: model.write_modes, FILES[1]: model.write_npz}
    result.metadata.update(linearized_at=model.linearized_at,
                           frequencies_hz=model.frequency_hz.tolist(),
                           damping_ratios=model.damping_ratio.tolist())
    return result


def _run_to(functions: SystemFunctions, settings: Analysis, at: float, progress,
            dynamics: Callable | None, workspace: Workspace | None) -> Result:
    """The dynamics run from 0 to `at` (`dynamics` with the settings' tolerances, formulation
    and dynamics solver; at = 0: the assembled initial state), its last row at `at`."""
    if not 0.0 <= at <= settings.t_end:
        raise UsageError(f"modal at = {at:g}: must be a time of the run, within [0, t_end = "
                         f"{settings.t_end:g}]")
    options = settings.options.dynamics()
    if at == 0.0:
        result = kinematics.run_assembly(functions, 0.0, progress, options.solver.assembly,
                                         workspace)
    elif dynamics is None:
        raise UsageError("modal at a time after 0 needs the dynamics run (runtime.analyses)")
    else:
        result = dynamics(functions, replace(settings, type="dynamics", t_end=at,
                                             output_step=min(settings.output_step, at),
                                             options=options), progress)
    if not result.times or abs(result.times[-1] - at) > 1e-12 * max(at, 1.0):
        last = result.times[-1] if result.times else 0.0
        raise AnalysisError(FailureContext(last, f"the run ended ({result.status}) before the "
                                           f"linearization time at = {at:.10g}"), result)
    result.analysis = "modal"
    return result
