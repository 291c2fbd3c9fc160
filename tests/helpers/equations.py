"""Shared builders for the tests of equations, elements, formulations and core.

Two kinds of things live here:
- plain-numpy geometry (A, G, E, B, skew, quaternions, rigid motions), written from the formulas of
  docs/architecture.md / Haug (1989) independently of casmech.core.euler, so that tests can
  compare the code under test against it;
- hand-built models: `ResolvedModel`s (schema contract) compiled with model.lower.lower and
  equations.functions.build_functions, without going through YAML.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.core.expressions import parse
from casmech.equations.functions import SystemFunctions, build_functions
from casmech.formulations import dae, residuals
from casmech.model.lower import lower
from casmech.schema.resolved import Analysis, Body, Force, Joint, ResolvedModel, ScalarFunction

# ---------------------------------------------------------------------------------------------
# numpy geometry


def dense(x) -> np.ndarray:
    """A CasADi matrix (DM) as a dense 2-D numpy array."""
    return np.array(ca.DM(x).full())


def skew(a) -> np.ndarray:
    a = np.asarray(a, float)
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def rotation(p) -> np.ndarray:
    """A(p) = E(p) G(p)^T = (e0^2 - e^T e) I + 2 e e^T + 2 e0 e~ (Haug 1989, ch. 6).

    On unit p this equals 2[(e0^2 - 1/2) I + e e^T + e0 e~]; off the unit sphere only this
    homogeneous form has d(A(p) a_bar)/dp = B(p, a_bar) (the lecture's delta-p flavour uses it).
    """
    e0, e = p[0], np.asarray(p[1:4], float)
    return (e0**2 - e @ e) * np.eye(3) + 2.0 * np.outer(e, e) + 2.0 * e0 * skew(e)


def g_matrix(p) -> np.ndarray:
    """G(p) = [-e, -e~ + e0 I]."""
    e0, e = p[0], np.asarray(p[1:4], float)
    return np.column_stack([-e, -skew(e) + e0 * np.eye(3)])


def e_matrix(p) -> np.ndarray:
    """E(p) = [-e, e~ + e0 I]."""
    e0, e = p[0], np.asarray(p[1:4], float)
    return np.column_stack([-e, skew(e) + e0 * np.eye(3)])


def b_matrix(p, a_bar) -> np.ndarray:
    """B(p, a_bar) = 2[(e0 I + e~) a_bar, e a_bar^T - (e0 I + e~) a_bar~]."""
    e0, e = p[0], np.asarray(p[1:4], float)
    a_bar = np.asarray(a_bar, float)
    m = e0 * np.eye(3) + skew(e)
    return 2.0 * np.column_stack([m @ a_bar, np.outer(e, a_bar) - m @ skew(a_bar)])


def axis_angle_p(axis, angle: float) -> np.ndarray:
    """Euler parameters of a rotation by `angle` about the unit `axis`."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    return np.r_[np.cos(angle / 2), np.sin(angle / 2) * axis]


def rodrigues(axis, angle: float) -> np.ndarray:
    """Rotation matrix by Rodrigues' formula (independent of A(p))."""
    k = skew(np.asarray(axis, float) / np.linalg.norm(axis))
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def quat_product(a, b) -> np.ndarray:
    """Hamilton product: A(a * b) = A(a) A(b)."""
    a0, av, b0, bv = a[0], np.asarray(a[1:]), b[0], np.asarray(b[1:])
    return np.r_[a0 * b0 - av @ bv, a0 * bv + b0 * av + np.cross(av, bv)]


def unit(v) -> np.ndarray:
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def random_unit_p(rng: np.random.Generator) -> np.ndarray:
    """A random unit quaternion, kept away from the identity (every entry of A non-trivial)."""
    return unit(rng.normal(size=4))


def rotate_pose(r, p, axis, angle: float, point) -> tuple[np.ndarray, np.ndarray]:
    """Pose of a body after a rigid rotation by `angle` about the global `axis` through `point`."""
    point = np.asarray(point, float)
    r_new = point + rodrigues(axis, angle) @ (np.asarray(r, float) - point)
    return r_new, quat_product(axis_angle_p(axis, angle), p)


def perpendicular(w) -> np.ndarray:
    """Some unit vector perpendicular to w."""
    w = unit(w)
    trial = np.eye(3)[int(np.argmin(np.abs(w)))]
    return unit(trial - (trial @ w) * w)


# ---------------------------------------------------------------------------------------------
# hand-built models


def scalar(text: str, variables: tuple[str, ...] = ("t",)) -> ScalarFunction:
    """A function of time (or of `variables`) from the expression language."""
    return ScalarFunction(text, parse(text), {}, variables)


def body(name: str, position, p, mass: float = 1.0, inertia=None) -> Body:
    inertia = np.diag([1.0, 2.0, 3.0]) if inertia is None else np.asarray(inertia, float)
    return Body(name, float(mass), inertia, np.asarray(position, float), np.asarray(p, float),
                np.zeros(3), np.zeros(3))


def joint(name: str, type_: str, body_i: str, body_j: str, **kwargs) -> Joint:
    """A joint; vector keys (at, axis, a_i, s_j, c, ...) go to `vectors`, `driver_<kind>` to
    its drivers (a coordinate kind's f(t)), the rest to Joint."""
    fields = {"length", "f", "options"}
    drivers = {k.removeprefix("driver_"): v for k, v in kwargs.items() if k.startswith("driver_")}
    vectors = {k: np.asarray(v, float) for k, v in kwargs.items()
               if k not in fields and not k.startswith("driver_")}
    return Joint(name, type_, body_i, body_j, vectors, drivers=drivers,
                 **{k: v for k, v in kwargs.items() if k in fields})


def model(bodies, joints=(), forces=(), gravity=(0.0, 0.0, 0.0)) -> ResolvedModel:
    return ResolvedModel("test", "", "test.yaml", "", {}, np.asarray(gravity, float),
                         tuple(bodies), tuple(joints), tuple(forces), Analysis())


def compile_model(resolved: ResolvedModel) -> SystemFunctions:
    return build_functions(lower(resolved))


def coordinates(bodies) -> np.ndarray:
    """q = [r_1..r_nb, p_1..p_nb] of the bodies' initial poses."""
    return np.concatenate([b.position for b in bodies] + [b.euler_parameters for b in bodies])


def stack_q(poses) -> np.ndarray:
    """q from a list of (r, p) per body."""
    return np.concatenate([r for r, _ in poses] + [p for _, p in poses])


def force(name: str, type_: str, **kwargs) -> Force:
    """A force element; vector keys (at, at_i, at_j) go to `vectors`."""
    vector_keys = {"at", "at_i", "at_j"}
    vectors = {k: np.asarray(v, float) for k, v in kwargs.items() if k in vector_keys}
    return Force(name, type_, vectors=vectors,
                 **{k: v for k, v in kwargs.items() if k not in vector_keys})


def rank(matrix: np.ndarray, relative: float = 1e-9) -> int:
    """Numerical rank: singular values above `relative` times the largest."""
    s = np.linalg.svd(matrix, compute_uv=False)
    return int(np.sum(s > relative * s[0]))


def two_free_bodies(rng: np.random.Generator) -> tuple[Body, Body]:
    """Bodies 'b1' and 'b2' with non-trivial orientations, CMs apart, full inertia tensors."""
    def inertia():
        m = rng.normal(size=(3, 3))
        return m @ m.T + 3 * np.eye(3)  # symmetric positive definite, not diagonal

    return (body("b1", [0.3, -0.2, 1.1] + 0.1 * rng.normal(size=3), random_unit_p(rng),
                 mass=1.7, inertia=inertia()),
            body("b2", [1.4, 0.6, 0.5] + 0.1 * rng.normal(size=3), random_unit_p(rng),
                 mass=0.8, inertia=inertia()))


def assert_mapped_residual_is_inline(ir, form: str, kind: str) -> None:
    """The mapped DAE residual (summed by element kernels) equals the inline one (one graph
    over the whole model's matrices) at random arguments."""
    inline = dae.residual(build_functions(ir).functions, form, kind)
    mapped = residuals.oracle(ir, form, kind)[residuals.name(form, kind)]
    rng = np.random.default_rng(3)
    for _ in range(2):
        args = [rng.uniform(-1, 1, inline.sparsity_in(k).shape) for k in range(4)]
        for k, (got, want) in enumerate(zip(mapped(*args, []), inline(*args), strict=False)):
            # the same equations, summed by element or as one graph: round-off
            np.testing.assert_allclose(dense(got), dense(want), rtol=1e-12, atol=1e-11,
                                       err_msg=f"{form} {kind} output {k}")
