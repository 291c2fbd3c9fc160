"""Linearization and modes at the static equilibrium (runtime.statics).

Independent coordinates: z with q = q* + N z, N the orthonormal null-space basis of Phi_q(q*)
from a column-pivoted QR of Phi_q^T (statics.null_space; Euler-parameter normalization rows
included, so z never changes a quaternion's norm). Projecting M q_ddot + Phi_q^T lam = Q on N
removes the multipliers; to first order about the equilibrium (where Q - Phi_q^T lam* = 0)

    M_r z'' + C_r z' + K_r z = 0,   M_r = N^T M N,  C_r = -N^T dQ/dq_dot N,
    K_r = -N^T d(Q - Phi_q^T lam*)/dq N   (lam* fixed: the constraint-curvature term),

all derivatives by CasADi's AD (statics.tangent_function). State x = [z; z'],
A = [[0, I], [-M_r^-1 K_r, -M_r^-1 C_r]]. Inputs u: a torque or force added to each effort
motor (`<joint>.torque` / `<joint>.force`; none without effort motors), B = [0; M_r^-1 N^T
G] with G the motors' generalized forces per unit input. Outputs y = C x (D = 0): every
body's translation and small global rotation (2 E(p) dp) away from the equilibrium:
`<body>.dx .dy .dz .rx .ry .rz`.

Modes: the eigenvalues s of A, a complex pair once (Im s > 0), a real eigenvalue (an
overdamped motion) on its own, a DOF of zero stiffness as one mode at s = 0;
frequency_hz = |s| / 2 pi (undamped natural frequency), damped_frequency_hz = |Im s| / 2 pi,
damping_ratio = -Re s / |s|; sorted by frequency. Mode shapes: the eigenvector's z mapped to
body motions (n_modes x n_bodies x 6), scaled so that the largest entry is 1.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import casadi as ca
import numpy as np

from casmech.compiler import motors as compiler_motors
from casmech.compiler.assemble import Coordinates
from casmech.compiler.functions import SystemFunctions
from casmech.output.atomic import atomic
from casmech.runtime import statics
from casmech.runtime.results import Result

MODE_COLUMNS = ("mode", "frequency_hz", "damping_ratio", "eigenvalue_real", "eigenvalue_imag",
                "damped_frequency_hz")
MOTION = ("dx", "dy", "dz", "rx", "ry", "rz")
# what a modal run writes beside results.csv (commands/run.py's ANALYSIS_FILES names them too,
# to remove an earlier run's without importing this module)
FILES = ("modes.csv", "linear_model.npz")
REAL_CUT = 1e-9  # |Im s| <= REAL_CUT |s|: a real eigenvalue


@dataclass
class LinearModel:
    """x' = A x + B u, y = C x + D u about the equilibrium q (states z, z'), and its modes."""

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
        """linear_model.npz, atomically (output.atomic)."""
        path = Path(path)
        with atomic(path, "wb") as handle:
            np.savez(handle, A=self.A, B=self.B, C=self.C, D=self.D,
                     state_names=np.array(self.state_names, dtype=str),
                     input_names=np.array(self.input_names, dtype=str),
                     output_names=np.array(self.output_names, dtype=str),
                     q_equilibrium=self.q, basis=self.basis, eigenvalues=self.eigenvalues,
                     mode_shapes=self.mode_shapes, mode_vectors=self.mode_vectors,
                     mode_shape_names=np.array(
                         [f"{b}.{m}" for b in self.body_names for m in MOTION], dtype=str))
        return path


def linearize(functions: SystemFunctions, system: statics.ReducedSystem) -> LinearModel:
    """The linear model and modes at an equilibrium's reduced system."""
    k = system.dof
    stiffness = np.linalg.solve(system.mass, system.stiffness) if k else np.zeros((0, 0))
    damping = np.linalg.solve(system.mass, system.damping) if k else np.zeros((0, 0))
    a = np.block([[np.zeros((k, k)), np.eye(k)], [-stiffness, -damping]])
    names, generalized = _inputs(functions, system.q)
    driven = np.linalg.solve(system.mass, system.basis.T @ generalized) if k else \
        np.zeros((0, len(names)))
    b = np.vstack([np.zeros((k, len(names))), driven])
    outputs = _output_map(functions, system)
    c = np.hstack([outputs, np.zeros_like(outputs)])
    eigenvalues, shapes, vectors = _modes(functions, system, a)
    bodies = list(functions.body_names)
    return LinearModel(
        A=a, B=b, C=c, D=np.zeros((c.shape[0], len(names))),
        state_names=[f"z{i + 1}" for i in range(k)] + [f"z{i + 1}_dot" for i in range(k)],
        input_names=names, output_names=[f"{body}.{m}" for body in bodies for m in MOTION],
        q=system.q, basis=system.basis, eigenvalues=eigenvalues, mode_shapes=shapes,
        body_names=bodies, mode_vectors=vectors)


INPUT_NAMES = {"motor_torque": "torque", "motor_force": "force"}


def _inputs(functions: SystemFunctions, q: np.ndarray) -> tuple[list[str], np.ndarray]:
    """The inputs: a torque or force added to each effort motor's (`<joint>.torque`,
    `<joint>.force`), and their generalized forces at q (n x inputs): the gradient of the joint
    coordinate the motor drives (virtual work, as compiler.motors applies it)."""
    motors = functions.ir.motors
    if not motors:
        return [], np.zeros((q.size, 0))
    x = Coordinates.create(functions.n_bodies)
    columns = [x.ground_fixed(ca.jacobian(compiler_motors.COORDINATE[m.type](m, x), x.q).T)
               for m in motors]
    gradient = ca.Function("motor_inputs", [x.q], [ca.horzcat(*columns)])
    return ([f"{m.name}.{INPUT_NAMES[m.type]}" for m in motors],
            np.array(gradient(q)).reshape(q.size, len(motors)))


def _output_map(functions: SystemFunctions, system: statics.ReducedSystem) -> np.ndarray:
    """(6 n_bodies, k): z -> every body's translation and small rotation."""
    return statics.motion_map(system.q) @ system.basis


def _modes(functions: SystemFunctions, system: statics.ReducedSystem, a: np.ndarray):
    """(eigenvalues one per mode, sorted by |s|; mode shapes as body motions; the same modes
    in z, scaled alike: N z is the shape's motion of the coordinates). A DOF of zero
    stiffness is one mode at s = 0 shaped as its null vector of K (A's eigenvalues there, a
    double zero or 0 and a real decay, are split by roundoff: |s| <= sqrt(neutral_threshold)
    counts as 0)."""
    k = system.dof
    if not k:
        return (np.zeros(0, complex), np.zeros((0, functions.n_bodies, 6), complex),
                np.zeros((0, 0), complex))
    threshold = statics.neutral_threshold(system.omega2())
    neutral = system.basis.T @ statics.neutral_directions(system)  # N orthonormal
    values, vectors = np.linalg.eig(a)
    size = np.abs(values)
    real = np.abs(values.imag) <= REAL_CUT * np.maximum(size, 1e-300)
    keep = (real | (values.imag > 0)) & (size > np.sqrt(threshold))
    values, vectors = np.where(real, values.real, values)[keep], vectors[:k, keep]
    values = np.concatenate([np.zeros(neutral.shape[1]), values]).astype(complex)
    vectors = np.hstack([neutral, vectors]).astype(complex)
    order = np.lexsort((-values.real, np.abs(values)))
    vectors = vectors[:, order]
    motions = statics.motion_map(system.q) @ system.basis @ vectors
    shapes, scaled = [], []
    for motion, vector in zip(motions.T, vectors.T, strict=True):
        largest = motion[np.argmax(np.abs(motion))]
        scale = 1 / largest if abs(largest) > 0 else 1.0
        shapes.append((scale * motion).reshape(-1, 6))
        scaled.append(scale * vector)
    return (values[order], np.array(shapes).reshape(len(order), functions.n_bodies, 6),
            np.array(scaled).T.reshape(k, len(order)))


def run_modal(functions: SystemFunctions, t: float = 0.0, progress=None) -> Result:
    """The modal analysis: the equilibrium row (statics), the linear model and the modes; a
    zero-stiffness DOF is kept (a zero-frequency mode), no equilibrium is an AnalysisError."""
    equilibrium = statics.solve(functions, t)
    result = statics.equilibrium_result(functions, t, equilibrium, "modal", progress)
    model = linearize(functions, equilibrium.system)
    result.linear_model = model
    result.files = {FILES[0]: model.write_modes, FILES[1]: model.write_npz}
    result.metadata.update(frequencies_hz=model.frequency_hz.tolist(),
                           damping_ratios=model.damping_ratio.tolist())
    return result
