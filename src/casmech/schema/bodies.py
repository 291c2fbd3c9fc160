"""Bodies: mass, inertia, orientation (every form -> unit Euler parameters), geometry."""

from __future__ import annotations

from typing import Any

import numpy as np

from casmech.core import euler, quaternions, traced
from casmech.errors import failed
from casmech.schema import files, resolved, scale, spec
from casmech.schema.checker import Checker
from casmech.schema.loader import Path

UNIT = 1e-9  # tolerance of unit norms, orthonormality, det = 1, inertia symmetry and triangle
PARALLEL = 1e-6  # |sin| below which two orientation axes are parallel
ORIENTATION_FORMS = ("euler_parameters", "axis_angle", "matrix", "x_axis", "y_axis", "z_axis")
AXES = ("x_axis", "y_axis", "z_axis")
CROSS = {"x_axis": AXES[1:], "y_axis": AXES[2::-2], "z_axis": AXES[:2]}  # right-handed third axis
IDENTITY = np.array([1.0, 0.0, 0.0, 0.0])

INERTIA_FORMS = {
    3: lambda v: traced.array(np.diag(v)),  # principal moments
    6: lambda v: traced.array([[v[0], v[3], v[4]], [v[3], v[1], v[5]], [v[4], v[5], v[2]]]),
}
GEOMETRY_SIZES = {  # kind -> {resolved key: (path inside the item, value)}, all must be > 0
    "box": lambda g: {"size": (("box",), g.box)},
    "cylinder": lambda g: {
        "radius": (("cylinder", "radius"), g.cylinder.radius),
        "length": (("cylinder", "length"), g.cylinder.length),
    },
    "sphere": lambda g: {"radius": (("sphere",), g.sphere)},
    "mesh": lambda g: {"scale": (("scale",), g.scale)},
}
GEOMETRY_EXTRAS = {
    "box": lambda g: {},
    "cylinder": lambda g: {"axis": g.cylinder.axis},
    "sphere": lambda g: {},
    "mesh": lambda g: {"file": g.mesh},
}


# ------------------------------------------------------------------------------ rotations
def rotation_matrix(p: np.ndarray) -> np.ndarray:
    """A(p): body -> global; columns are the body axes (core/euler.py's, on numbers or
    traced numbers)."""
    return traced.numeric(euler.rotation, traced.asarray(p))


# ---------------------------------------------------------------------------------- checks
def orientation(check: Checker, path: Path, given: spec.Orientation | None) -> np.ndarray | None:
    if given is None:
        return IDENTITY.copy()
    forms = [form for form in ORIENTATION_FORMS if getattr(given, form) is not None]
    axes = [form for form in forms if form in AXES]
    kinds = [form for form in forms if form not in AXES] + (["two axes"] if axes else [])
    if len(kinds) != 1 or len(axes) not in (0, 2):
        got = ", ".join(forms) or "none"
        check.error(
            "E407",
            path,
            "orientation needs exactly one form",
            got=got,
            expected="euler_parameters, axis_angle, matrix, or two of x_axis, y_axis, z_axis",
        )
        return None
    return ORIENTATIONS[kinds[0]](check, path, given)


def from_euler_parameters(check: Checker, path: Path, given: spec.Orientation) -> np.ndarray | None:
    path = (*path, "euler_parameters")
    p = check.numbers(path, given.euler_parameters)
    if p is None:
        return None
    norm = np.linalg.norm(p)
    if abs(norm - 1.0) > UNIT:
        unit = "[" + ", ".join(f"{x:.12g}" for x in p / norm) + "]" if norm else None
        got = f"norm {norm:.12g}"
        hint = f"normalised: {unit}" if unit else None
        check.error("E403", path, "Euler parameters must have unit norm", got=got, hint=hint)
        return None
    return p / norm


def from_axis_angle(check: Checker, path: Path, given: spec.Orientation) -> np.ndarray | None:
    path = (*path, "axis_angle")
    axis = check.direction((*path, "axis"), given.axis_angle.axis)
    angle = check.number((*path, "angle"), given.axis_angle.angle)
    if axis is None or angle is None:
        return None
    return traced.array(np.concatenate([[traced.cos(angle / 2)], traced.sin(angle / 2) * axis]))


def from_matrix(check: Checker, path: Path, given: spec.Orientation) -> np.ndarray | None:
    path = (*path, "matrix")
    rows = [check.numbers((*path, row), values) for row, values in enumerate(given.matrix)]
    if failed(rows):
        return None
    a = traced.array(rows)
    values = traced.value(a)
    error, det = np.abs(values.T @ values - np.eye(3)).max(), np.linalg.det(values)
    if error > UNIT or abs(det - 1.0) > UNIT:
        check.error(
            "E406",
            path,
            "rotation matrix must be orthonormal with det = +1",
            got=f"max |A^T A - I| = {error:.3g}, det = {det:.12g}",
            hint="columns are the body x, y, z axes in the global frame",
        )
        return None
    return quaternions.from_matrix(a)


def from_axes(check: Checker, path: Path, given: spec.Orientation) -> np.ndarray | None:
    first, second = (form for form in AXES if getattr(given, form) is not None)
    u = check.direction((*path, first), getattr(given, first))
    v = check.direction((*path, second), getattr(given, second))
    if u is None or v is None:
        return None
    v = v - (v @ u) * u
    if np.linalg.norm(v) < PARALLEL:
        check.error("E405", (*path, second), f"{first} and {second} are parallel")
        return None
    axes = {first: u, second: v / np.linalg.norm(v)}
    third = next(form for form in AXES if form not in axes)
    axes[third] = np.cross(*(axes[form] for form in CROSS[third]))
    return quaternions.from_matrix(np.column_stack([axes[form] for form in AXES]))


def inertia(check: Checker, path: Path, values) -> np.ndarray | None:
    nested = isinstance(values[0], tuple)  # the 3x3 form
    rows = [check.numbers((*path, r), row) for r, row in enumerate(values)] if nested else []
    rows = rows or [check.numbers(path, values)]
    if failed(rows):
        return None
    matrix = traced.array(rows) if nested else INERTIA_FORMS[len(values)](rows[0])
    numbers = traced.value(matrix)  # the checks read the values
    scale = np.abs(numbers).max()
    if np.abs(numbers - numbers.T).max() > UNIT * scale:
        check.error("E401", path, "inertia matrix is not symmetric")
        return None
    moments = np.linalg.eigvalsh(numbers)
    if moments[0] <= 0:
        check.error(
            "E401",
            path,
            "inertia is not positive definite",
            got=f"principal moments {', '.join(f'{m:g}' for m in moments)}",
        )
        return None
    if moments[0] + moments[1] < moments[2] * (1 - UNIT):
        check.error(
            "E402",
            path,
            "principal moments violate the triangle inequality",
            got="{:g} + {:g} < {:g}".format(*moments),
            hint="no rigid body has one moment larger than the sum of the other two",
        )
        return None
    return matrix


def geometry(check: Checker, path: Path, item) -> dict[str, Any] | None:
    kind = next(kind for kind in spec.GEOMETRY_KINDS if hasattr(item, kind))
    result: dict[str, Any] = {"type": kind, **GEOMETRY_EXTRAS[kind](item)}
    for key, (where, value) in GEOMETRY_SIZES[kind](item).items():
        where = (*path, *where)
        measure = check.numbers if isinstance(value, tuple) else check.number
        number = measure(where, value)
        if kind == "mesh" and isinstance(value, tuple):  # per axis: signs mirror
            result[key] = nonzero(check, where, number)
        else:
            result[key] = check.positive("E410", where, number, f"{kind} {key}")
    if kind == "mesh":
        result["file"] = mesh_file(check, (*path, "mesh"), item.mesh)
    result["offset"] = check.vector((*path, "offset"), item.offset)
    result["euler_parameters"] = orientation(check, (*path, "orientation"), item.orientation)
    return None if failed(result.values()) else result


def nonzero(check: Checker, path: Path, factors) -> np.ndarray | None:
    """A mesh's scale factors per axis if none is zero (a negative one mirrors that axis)."""
    if factors is not None and np.any(np.asarray(factors) == 0):
        check.error("E410", path, "mesh scale factors must be non-zero",
                    got=", ".join(f"{x:g}" for x in factors),
                    hint="a negative factor mirrors the mesh along that axis")
        return None
    return factors


def mesh_file(check: Checker, path: Path, name: str) -> str | None:
    """The mesh file as written, if it may be read (in the model's folder, a regular file when
    it exists; `casmech animate` reads it); None: reported (E305)."""
    try:
        files.resolve(check.doc.file, name, must_exist=False)
    except files.NotAllowed as error:
        check.error("E305", path, f"mesh file '{name}': {error.reason}", hint=error.hint)
        return None
    return name


def floors(check: Checker, bodies) -> None:
    """Masses and inertias below the floors of the model's scale (schema/scale.py), E411;
    call it once every body is resolved (`bodies`: in file order, None where reported)."""
    for index, item in enumerate(bodies):
        if item is None:
            continue
        path = ("bodies", index)
        mass = traced.value(item.mass)  # a check: on the values of traced numbers
        problem = scale.mass_problem(check.scale, mass)
        if problem is not None:
            check.error("E411", (*path, "mass"), problem[0], expected=problem[1],
                        got=f"{mass:.6g}", hint=problem[2])
        moments = np.linalg.eigvalsh(traced.value(item.inertia))
        problem = scale.inertia_problem(check.scale, moments)
        if problem is not None:
            check.error("E411", (*path, "inertia"), problem[0], expected=problem[1],
                        got=", ".join(f"{m:.6g}" for m in moments), hint=problem[2])


def body(check: Checker, index: int, given: spec.Body) -> resolved.Body | None:
    path = ("bodies", index)
    mass = check.positive(
        "E400", (*path, "mass"), check.number((*path, "mass"), given.mass), "mass"
    )
    moments = inertia(check, (*path, "inertia"), given.inertia)
    position = check.vector((*path, "position"), given.position)
    check.scale.add(given.name, mass, moments, position)  # before its orientation's axes
    fields = dict(
        mass=mass,
        inertia=moments,
        position=position,
        euler_parameters=orientation(check, (*path, "orientation"), given.orientation),
        velocity=check.vector((*path, "velocity"), given.velocity),
        angular_velocity=check.vector((*path, "angular_velocity"), given.angular_velocity),
        geometry=tuple(
            geometry(check, (*path, "geometry", k), item) for k, item in enumerate(given.geometry)
        ),
    )
    if failed([*fields.values(), *fields["geometry"]]):
        return None
    return resolved.Body(given.name, **fields, source=check.doc.locate(path))


ORIENTATIONS = {
    "euler_parameters": from_euler_parameters,
    "axis_angle": from_axis_angle,
    "matrix": from_matrix,
    "two axes": from_axes,
}
