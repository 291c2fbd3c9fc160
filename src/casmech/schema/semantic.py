"""ModelSpec -> ResolvedModel: cross-references, expression evaluation, physical sanity.

Every finding is collected (`Checker.found`); the caller raises them all at once. An item whose
check failed resolves to None, and references to a parameter that failed are not reported again.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from typing import Any

import numpy as np

from casmech.errors import Diagnostic, Source, did_you_mean
from casmech.schema import resolved, spec
from casmech.schema.expressions import CONSTANTS, FUNCTIONS, Expr, ExpressionError, from_number
from casmech.schema.expressions import parse as parse_expression
from casmech.schema.loader import Document, Path, format_path
from casmech.schema.resolved import GROUND, ScalarFunction

NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
RESERVED = frozenset({"t", *CONSTANTS, *FUNCTIONS})
ZERO = 1e-12  # a vector shorter than this is zero-length (its direction is meaningless)
UNIT = 1e-9  # tolerance of unit norms, orthonormality, det = 1, inertia symmetry and triangle
PERPENDICULAR = 1e-6  # |cos| above which two axes are not perpendicular
PARALLEL = 1e-6  # |sin| below which two orientation axes are parallel
TIME_KEYS = "joint f, driver angle/displacement, force/torque value, tsda/rsda actuator"

VECTOR_KEYS = ("at", "axis", "axis_i", "axis_j", "at_i", "at_j", "a_i", "a_j", "s_i", "s_j", "c")
UNIT_KEYS = frozenset({"axis", "axis_i", "axis_j"})  # normalised
NONZERO_KEYS = frozenset({"axis", "axis_i", "axis_j", "a_i", "a_j", "c"})  # E404 when zero
DRIVERS = {"angle": ("revolute", "cylindrical"), "displacement": ("translational", "cylindrical")}
RSDA_JOINTS = ("revolute", "cylindrical")
ORIENTATION_FORMS = ("euler_parameters", "axis_angle", "matrix", "x_axis", "y_axis", "z_axis")
AXES = ("x_axis", "y_axis", "z_axis")
CROSS = {"x_axis": AXES[1:], "y_axis": AXES[2::-2], "z_axis": AXES[:2]}  # right-handed third axis
IDENTITY = np.array([1.0, 0.0, 0.0, 0.0])


INERTIA_FORMS = {
    3: np.diag,  # principal moments
    6: lambda v: np.array([[v[0], v[3], v[4]], [v[3], v[1], v[5]], [v[4], v[5], v[2]]]),
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


def failed(values) -> bool:
    """Whether any of `values` is None (a check that failed and was reported)."""
    return any(value is None for value in values)


# ------------------------------------------------------------------------------ rotations
def skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rotation_matrix(p: np.ndarray) -> np.ndarray:
    """A(p) = 2[(e0^2 - 1/2) I + e e^T + e0 e~]: body -> global; columns are the body axes."""
    e0, e = p[0], np.asarray(p[1:])
    return 2.0 * ((e0 * e0 - 0.5) * np.eye(3) + np.outer(e, e) + e0 * skew(e))


def euler_parameters(a: np.ndarray) -> np.ndarray:
    """Shepperd's method: Euler parameters (e0 >= 0) of a rotation matrix."""
    trace = np.trace(a)
    k = np.array(
        [
            [1 + trace, a[2, 1] - a[1, 2], a[0, 2] - a[2, 0], a[1, 0] - a[0, 1]],
            [a[2, 1] - a[1, 2], 1 + 2 * a[0, 0] - trace, a[0, 1] + a[1, 0], a[0, 2] + a[2, 0]],
            [a[0, 2] - a[2, 0], a[0, 1] + a[1, 0], 1 + 2 * a[1, 1] - trace, a[1, 2] + a[2, 1]],
            [a[1, 0] - a[0, 1], a[0, 2] + a[2, 0], a[1, 2] + a[2, 1], 1 + 2 * a[2, 2] - trace],
        ]
    )  # k[i, j] = 4 p_i p_j
    largest = int(np.argmax(np.diag(k)))
    p = k[largest] / (2.0 * math.sqrt(k[largest, largest]))
    p = -p if p[0] < 0 else p
    return p / np.linalg.norm(p)


# ------------------------------------------------------------------------------- checker
class Checker:
    def __init__(self, document: Document, overrides: Mapping[str, str] | None):
        self.doc = document
        self.overrides = dict(overrides or {})
        self.found: list[Diagnostic] = []
        self.parameters: dict[str, float] = {}
        self.declared: dict[str, int] = {}  # parameter -> line, for "defined later"
        self.broken: set[str] = set()  # parameters that failed: no follow-up errors
        self.bodies: dict[str, resolved.Body | None] = {}
        self.joint_types: dict[str, str] = {}
        self.joint_bodies: dict[str, tuple[str, str]] = {}

    # -- reporting
    def error(self, code: str, path: Path | str, message: str, **extra: Any) -> None:
        if "source" not in extra:
            extra["source"] = self.doc.locate(path) if isinstance(path, tuple) else None
        text = format_path(path) if isinstance(path, tuple) else path
        self.found.append(Diagnostic(code, text, message, **extra))

    def inside(self, path: Path | str, offset: int) -> Source | None:
        return self.doc.source_in_scalar(path, offset) if isinstance(path, tuple) else None

    # -- expressions
    def expression(self, path: Path | str, value: Any, variables=()) -> Expr | None:
        """Parse and check the names of a scalar (E200, E201, E202, E203, E204)."""
        try:
            expr = parse_expression(value) if isinstance(value, str) else from_number(value)
        except ExpressionError as error:
            source = self.inside(path, error.offset)
            self.error(error.code, path, error.message, source=source, hint=error.hint)
            return None
        except OverflowError:
            self.error("E204", path, "number too large", got=str(value))
            return None
        known = [name not in self.broken for name in expr.symbols]
        for name, offset, _ in expr.names_with_offsets():
            if name not in self.parameters and name not in variables and name not in self.broken:
                self.unknown_symbol(path, name, self.inside(path, offset), variables)
                known.append(False)
        return expr if all(known) else None

    def unknown_symbol(self, path, name: str, source, variables) -> None:
        if name == "t":
            self.error(
                "E202",
                path,
                "time 't' is not allowed here",
                source=source,
                hint=f"functions of time are allowed in: {TIME_KEYS}",
            )
        elif name in self.declared:
            message = f"'{name}' is used before it is defined"
            hint = f"parameters are evaluated in order; '{name}' is defined at line "
            self.error("E201", path, message, source=source, hint=f"{hint}{self.declared[name]}")
        else:
            names = [*self.parameters, *variables, *CONSTANTS]
            hint = did_you_mean(name, names)
            self.error("E201", path, f"unknown symbol '{name}'", source=source, hint=hint)

    def finite(self, path, expr: Expr, at: Mapping[str, float]) -> float | None:
        value = float(expr.evaluate({**self.parameters, **at}, "numpy"))
        if not math.isfinite(value):
            where = ", ".join(f"{name} = {number:g}" for name, number in at.items())
            self.error(
                "E204",
                path,
                f"'{expr.text}' evaluates to {value}" + (f" at {where}" if where else ""),
            )
            return None
        return value

    def number(self, path: Path | str, value: Any) -> float | None:
        expr = self.expression(path, value)
        return None if expr is None else self.finite(path, expr, {})

    def function(self, path: Path, value: Any, at: Mapping[str, float]) -> ScalarFunction | None:
        variables = tuple(at)
        expr = self.expression(path, value, variables)
        if expr is None or self.finite(path, expr, at) is None:
            return None
        source = self.doc.locate(path)
        return ScalarFunction(str(value), expr, dict(self.parameters), variables, source)

    def numbers(self, path: Path, values) -> np.ndarray | None:
        items = [self.number((*path, index), value) for index, value in enumerate(values)]
        return None if failed(items) else np.array(items)

    def positive(self, code: str, path: Path, value, what: str) -> Any:
        """`value` (a number or an array) if all positive; else report and return None."""
        if value is not None and np.any(np.asarray(value) <= 0):
            got = ", ".join(f"{x:g}" for x in np.atleast_1d(value))
            self.error(code, path, f"{what} must be positive", got=got)
            return None
        return value

    def direction(self, path: Path, values, normalise: bool = True) -> np.ndarray | None:
        vector = self.numbers(path, values)
        if vector is None:
            return None
        norm = np.linalg.norm(vector)
        if norm < ZERO:
            self.error("E404", path, "zero-length vector: its direction is undefined")
            return None
        return vector / norm if normalise else vector

    # -- names
    def parameter_values(self, parameters: Mapping[str, Any]) -> None:
        self.declared = {
            name: self.doc.locate_key(("parameters", name)).line for name in parameters
        }
        for name in self.overrides.keys() - parameters.keys():
            hint = did_you_mean(name, parameters)
            self.error("E300", f"--set {name}", f"unknown parameter '{name}'", hint=hint)
        for name, value in parameters.items():
            path = ("parameters", name)
            if not self.valid_name(path, name, self.doc.locate_key(path), RESERVED):
                self.broken.add(name)
                continue
            where = f"--set {name}" if name in self.overrides else path
            result = self.number(where, self.overrides.get(name, value))
            del self.declared[name]
            self.parameters.update({name: result} if result is not None else {})
            self.broken.update({name} if result is None else set())

    def valid_name(self, path: Path, name: str, source: Source, reserved) -> bool:
        if not NAME.match(name):
            expected = "letters, digits and '_', not starting with a digit"
            self.error("E303", path, f"invalid name '{name}'", source=source, expected=expected)
        elif name in reserved:
            self.error(
                "E302",
                path,
                f"'{name}' is a reserved name",
                source=source,
                hint=f"reserved: {', '.join(sorted(reserved))}",
            )
        return bool(NAME.match(name)) and name not in reserved

    def unique_names(self, model: spec.ModelSpec) -> None:
        first: dict[str, Path] = {}
        for section in ("bodies", "joints", "forces"):
            for index, item in enumerate(getattr(model, section)):
                path = (section, index, "name")
                if not self.valid_name(path, item.name, self.doc.locate(path), {GROUND}):
                    continue
                if item.name in first:
                    where = first[item.name]
                    line = self.doc.locate(where).line
                    message = f"duplicate name '{item.name}' (first used by "
                    self.error("E301", path, f"{message}{format_path(where[:2])}, line {line})")
                first.setdefault(item.name, path)

    def reference(self, path: Path, name: str, known, what: str) -> bool:
        if name not in known:
            hint = did_you_mean(name, known)
            self.error("E300", path, f"unknown {what} '{name}'", hint=hint)
        return name in known

    def two_bodies(self, path: Path, body_i: str, body_j: str) -> bool:
        known = [GROUND, *self.bodies]
        found = all(
            [
                self.reference((*path, "body_i"), body_i, known, "body"),
                self.reference((*path, "body_j"), body_j, known, "body"),
            ]
        )
        if found and body_i == body_j:
            self.error("E304", (*path, "body_j"), f"body_i and body_j are both '{body_i}'")
        return found and body_i != body_j

    # -- bodies
    def orientation(self, path: Path, given: spec.Orientation | None) -> np.ndarray | None:
        if given is None:
            return IDENTITY.copy()
        forms = [form for form in ORIENTATION_FORMS if getattr(given, form) is not None]
        axes = [form for form in forms if form in AXES]
        kinds = [form for form in forms if form not in AXES] + (["two axes"] if axes else [])
        if len(kinds) != 1 or len(axes) not in (0, 2):
            got = ", ".join(forms) or "none"
            self.error(
                "E407",
                path,
                "orientation needs exactly one form",
                got=got,
                expected=f"one of euler_parameters, axis_angle, matrix, two of {AXES}",
            )
            return None
        return ORIENTATIONS[kinds[0]](self, path, given)

    def from_euler_parameters(self, path: Path, given: spec.Orientation) -> np.ndarray | None:
        path = (*path, "euler_parameters")
        p = self.numbers(path, given.euler_parameters)
        norm = None if p is None else np.linalg.norm(p)
        if norm is not None and abs(norm - 1.0) > UNIT:
            hint = (
                "normalised: [" + ", ".join(f"{x:.12g}" for x in p / norm) + "]" if norm else None
            )
            self.error(
                "E403",
                path,
                "Euler parameters must have unit norm",
                got=f"norm {norm:.12g}",
                hint=hint,
            )
            return None
        return None if p is None else p / norm

    def from_axis_angle(self, path: Path, given: spec.Orientation) -> np.ndarray | None:
        path = (*path, "axis_angle")
        axis = self.direction((*path, "axis"), given.axis_angle.axis)
        angle = self.number((*path, "angle"), given.axis_angle.angle)
        if axis is None or angle is None:
            return None
        return np.concatenate([[math.cos(angle / 2)], math.sin(angle / 2) * axis])

    def from_matrix(self, path: Path, given: spec.Orientation) -> np.ndarray | None:
        path = (*path, "matrix")
        rows = [self.numbers((*path, row), values) for row, values in enumerate(given.matrix)]
        if failed(rows):
            return None
        a = np.array(rows)
        error, det = np.abs(a.T @ a - np.eye(3)).max(), np.linalg.det(a)
        if error > UNIT or abs(det - 1.0) > UNIT:
            self.error(
                "E406",
                path,
                "rotation matrix must be orthonormal with det = +1",
                got=f"max |A^T A - I| = {error:.3g}, det = {det:.12g}",
                hint="columns are the body x, y, z axes in the global frame",
            )
            return None
        return euler_parameters(a)

    def from_axes(self, path: Path, given: spec.Orientation) -> np.ndarray | None:
        first, second = (form for form in AXES if getattr(given, form) is not None)
        u = self.direction((*path, first), getattr(given, first))
        v = self.direction((*path, second), getattr(given, second))
        if u is None or v is None:
            return None
        v = v - (v @ u) * u
        if np.linalg.norm(v) < PARALLEL:
            self.error("E405", (*path, second), f"{first} and {second} are parallel")
            return None
        axes = {first: u, second: v / np.linalg.norm(v)}
        third = next(form for form in AXES if form not in axes)
        axes[third] = np.cross(*(axes[form] for form in CROSS[third]))
        return euler_parameters(np.column_stack([axes[form] for form in AXES]))

    def inertia(self, path: Path, values) -> np.ndarray | None:
        nested = isinstance(values[0], tuple)
        rows = [self.numbers((*path, r), row) for r, row in enumerate(values)] if nested else []
        flat = None if nested else self.numbers(path, values)
        if failed([flat] if not nested else rows):
            return None
        matrix = np.array(rows) if nested else INERTIA_FORMS[len(flat)](flat)
        scale = np.abs(matrix).max()
        if np.abs(matrix - matrix.T).max() > UNIT * scale:
            self.error("E401", path, "inertia matrix is not symmetric")
            return None
        moments = np.linalg.eigvalsh(matrix)
        if moments[0] <= 0:
            self.error(
                "E401",
                path,
                "inertia is not positive definite",
                got=f"principal moments {', '.join(f'{m:g}' for m in moments)}",
            )
            return None
        if moments[0] + moments[1] < moments[2] * (1 - UNIT):
            self.error(
                "E402",
                path,
                "principal moments violate the triangle inequality",
                got="{:g} + {:g} < {:g}".format(*moments),
                hint="no rigid body has one moment larger than the sum of the other two",
            )
            return None
        return matrix

    def geometry(self, path: Path, item) -> dict[str, Any] | None:
        kind = next(kind for kind in spec.GEOMETRY_KINDS if hasattr(item, kind))
        result: dict[str, Any] = {"type": kind, **GEOMETRY_EXTRAS[kind](item)}
        for key, (where, value) in GEOMETRY_SIZES[kind](item).items():
            where = (*path, *where)
            number = (
                self.numbers(where, value)
                if isinstance(value, tuple)
                else (self.number(where, value))
            )
            result[key] = self.positive("E410", where, number, f"{kind} {key}")
        result["offset"] = self.vector((*path, "offset"), item.offset)
        result["euler_parameters"] = self.orientation((*path, "orientation"), item.orientation)
        return None if failed(result.values()) else result

    def vector(self, path: Path, values, default=(0.0, 0.0, 0.0)) -> np.ndarray | None:
        return np.array(default, float) if values is None else self.numbers(path, values)

    def body(self, index: int, given: spec.Body) -> resolved.Body | None:
        path = ("bodies", index)
        mass = self.positive(
            "E400", (*path, "mass"), self.number((*path, "mass"), given.mass), "mass"
        )
        fields = dict(
            mass=mass,
            inertia=self.inertia((*path, "inertia"), given.inertia),
            position=self.vector((*path, "position"), given.position),
            euler_parameters=self.orientation((*path, "orientation"), given.orientation),
            velocity=self.vector((*path, "velocity"), given.velocity),
            angular_velocity=self.vector((*path, "angular_velocity"), given.angular_velocity),
            geometry=tuple(
                self.geometry((*path, "geometry", k), item) for k, item in enumerate(given.geometry)
            ),
        )
        if failed([*fields.values(), *fields["geometry"]]):
            return None
        return resolved.Body(given.name, **fields, source=self.doc.locate(path))

    # -- joints
    def joint(self, index: int, given) -> resolved.Joint | None:
        path = ("joints", index)
        bodies_ok = self.two_bodies(path, given.body_i, given.body_j)
        self.joint_types[given.name] = given.type
        self.joint_bodies[given.name] = (given.body_i, given.body_j)
        keys = [key for key in VECTOR_KEYS if key in type(given).model_fields]
        vectors = {key: self.joint_vector((*path, key), key, getattr(given, key)) for key in keys}
        extra = (
            {"length": self.distance_length(path, given, vectors)}
            if given.type == "distance"
            else {}
        )
        extra.update(self.drivers(path, given))
        if given.type in JOINT_CHECKS and not failed(vectors.values()):
            JOINT_CHECKS[given.type](self, path, vectors)
        if hasattr(given, "f"):
            extra["f"] = self.function((*path, "f"), given.f, {"t": 0.0})
        if not bodies_ok or failed([*vectors.values(), *extra.values()]):
            return None
        sources = {key: self.doc.locate_key((*path, key)) for key in given.model_fields_set}
        if given.driver is not None if hasattr(given, "driver") else False:
            sources.update(
                {
                    f"driver.{key}": self.doc.locate_key((*path, "driver", key))
                    for key in given.driver.model_fields_set
                }
            )
        return resolved.Joint(
            given.name,
            given.type,
            given.body_i,
            given.body_j,
            vectors,
            **extra,
            source=self.doc.locate(path),
            sources=sources,
        )

    def joint_vector(self, path: Path, key: str, values) -> np.ndarray | None:
        if key in NONZERO_KEYS:
            return self.direction(path, values, normalise=key in UNIT_KEYS)
        return self.numbers(path, values)

    def drivers(self, path: Path, given) -> dict[str, ScalarFunction | None]:
        driver = getattr(given, "driver", None)
        found = {}
        for key in [] if driver is None else sorted(driver.model_fields_set):
            where = (*path, "driver", key)
            if given.type not in DRIVERS[key]:
                allowed = " and ".join(DRIVERS[key])
                self.error(
                    "E408",
                    where,
                    f"a {key} driver is not allowed on a {given.type} joint",
                    source=self.doc.locate_key(where),
                    hint=f"allowed on {allowed} joints",
                )
                found[key] = None
            else:
                found[f"driver_{key}"] = self.function(where, getattr(driver, key), {"t": 0.0})
        return found

    def distance_length(self, path: Path, given, vectors) -> float | None:
        if given.length is not None:
            length = self.number((*path, "length"), given.length)
            where = (*path, "length")
        elif failed(vectors.values()):
            return None
        else:
            length, where = float(np.linalg.norm(vectors["at_j"] - vectors["at_i"])), path
        if length is not None and length <= ZERO:
            self.error(
                "E404",
                where,
                "a distance joint needs a positive length",
                got=f"{length:g}",
                hint="use a spherical joint for coincident points",
            )
            return None
        return length

    def check_universal(self, path: Path, vectors) -> None:
        cosine = abs(vectors["axis_i"] @ vectors["axis_j"])
        if cosine > PERPENDICULAR:
            self.error(
                "E405",
                (*path, "axis_j"),
                "axis_i and axis_j must be perpendicular",
                got=f"|cos| = {cosine:.3g}",
            )

    def check_revolute_spherical(self, path: Path, vectors) -> None:
        arm = vectors["at_j"] - vectors["at"]
        length = np.linalg.norm(arm)
        if length < ZERO:
            self.error(
                "E404",
                (*path, "at_j"),
                "at_j coincides with at",
                hint="the arm from `at` to `at_j` must have a positive length",
            )
        elif abs(arm @ vectors["axis"]) > PERPENDICULAR * length:
            self.error(
                "E405",
                (*path, "at_j"),
                "at_j - at must be perpendicular to axis",
                got=f"|cos| = {abs(arm @ vectors['axis']) / length:.3g}",
            )

    # -- forces
    def force(self, index: int, given) -> resolved.Force | None:
        path = ("forces", index)
        fields = FORCES[given.type](self, path, given)
        if fields is None or failed([*fields.values(), *fields.get("value", ())]):
            return None
        return resolved.Force(given.name, given.type, **fields, source=self.doc.locate(path))

    def tsda(self, path: Path, given) -> dict[str, Any] | None:
        bodies_ok = self.two_bodies(path, given.body_i, given.body_j)
        at = {key: self.numbers((*path, key), getattr(given, key)) for key in ("at_i", "at_j")}
        if not bodies_ok or failed(at.values()):
            return None
        length = float(np.linalg.norm(at["at_j"] - at["at_i"]))
        free = (
            length
            if given.free_length is None
            else (self.number((*path, "free_length"), given.free_length))
        )
        at_zero = {"t": 0.0, "length": length, "length_dot": 0.0}
        return dict(
            body_i=given.body_i,
            body_j=given.body_j,
            vectors=at,
            free_length=free,
            **self.coefficients(path, given),
            actuator=self.function((*path, "actuator"), given.actuator, at_zero),
        )

    def rsda(self, path: Path, given) -> dict[str, Any] | None:
        joint = (*path, "joint")
        if not self.reference(joint, given.joint, list(self.joint_types), "joint"):
            return None
        if self.joint_types[given.joint] not in RSDA_JOINTS:
            self.error(
                "E103",
                joint,
                "an rsda acts about the axis of a revolute or cylindrical joint",
                got=f"'{given.joint}' is {self.joint_types[given.joint]}",
            )
            return None
        body_i, body_j = self.joint_bodies[given.joint]
        at_zero = {"t": 0.0, "angle": 0.0, "angle_dot": 0.0}
        return dict(
            joint=given.joint,
            body_i=body_i,
            body_j=body_j,
            free_angle=self.number((*path, "free_angle"), given.free_angle),
            **self.coefficients(path, given),
            actuator=self.function((*path, "actuator"), given.actuator, at_zero),
        )

    def coefficients(self, path: Path, given) -> dict[str, float | None]:
        return {
            key: self.number((*path, key), getattr(given, key)) for key in ("stiffness", "damping")
        }

    def load(self, path: Path, given) -> dict[str, Any] | None:
        """A point force or a torque on one moving body."""
        if not self.reference((*path, "body"), given.body, list(self.bodies), "moving body"):
            return None
        value = tuple(
            self.function((*path, "value", k), component, {"t": 0.0})
            for k, component in enumerate(given.value)
        )
        fields = dict(body=given.body, value=value, frame=given.frame)
        if given.type == "force":
            body = self.bodies[given.body]
            default = None if body is None else body.position
            at = self.vector((*path, "at"), given.at, default) if default is not None else None
            fields["vectors"] = None if at is None else {"at": at}
        return fields

    # -- analysis and model
    def analysis(self, given: spec.Analysis) -> resolved.Analysis | None:
        path = ("analysis",)
        keys = ("t_end", "output_step", "rtol", "atol")
        values = {key: self.number((*path, key), getattr(given, key)) for key in keys}
        for key, rule in ANALYSIS_RULES.items():
            problem = None if failed(values.values()) else rule(values)
            if problem:
                self.error("E409", (*path, key), problem, got=f"{values[key]:g}")
        if self.found_in(path) or failed(values.values()):
            return None
        return resolved.Analysis(
            given.type,
            **values,
            options={"formulation": given.formulation},
            source=self.doc.source_map.values.get(path),
        )

    def found_in(self, path: Path) -> bool:
        prefix = format_path(path)
        return any(d.path.startswith(prefix) for d in self.found)

    def model(self, given: spec.ModelSpec) -> resolved.ResolvedModel | None:
        self.parameter_values(given.parameters)
        self.unique_names(given)
        gravity = self.numbers(("gravity",), given.gravity)
        bodies = []
        for index, body in enumerate(given.bodies):
            bodies.append(self.body(index, body))
            self.bodies.setdefault(body.name, bodies[-1])
        joints = [self.joint(index, joint) for index, joint in enumerate(given.joints)]
        forces = [self.force(index, force) for index, force in enumerate(given.forces)]
        analysis = self.analysis(given.analysis)
        if self.found:
            return None
        return resolved.ResolvedModel(
            given.name,
            given.description,
            self.doc.file,
            self.doc.text,
            dict(self.parameters),
            gravity,
            tuple(bodies),
            tuple(joints),
            tuple(forces),
            analysis,
        )


ORIENTATIONS = {
    "euler_parameters": Checker.from_euler_parameters,
    "axis_angle": Checker.from_axis_angle,
    "matrix": Checker.from_matrix,
    "two axes": Checker.from_axes,
}
JOINT_CHECKS = {
    "universal": Checker.check_universal,
    "revolute_spherical": Checker.check_revolute_spherical,
}
FORCES = {"tsda": Checker.tsda, "rsda": Checker.rsda, "force": Checker.load, "torque": Checker.load}
ANALYSIS_RULES = {
    "t_end": lambda v: "t_end must be positive" if v["t_end"] <= 0 else None,
    "output_step": lambda v: (
        "output_step must be positive and at most t_end"
        if not 0 < v["output_step"] <= v["t_end"]
        else None
    ),
    "rtol": lambda v: "rtol must be positive" if v["rtol"] <= 0 else None,
    "atol": lambda v: "atol must be positive" if v["atol"] <= 0 else None,
}


def resolve(
    document: Document,
    model: spec.ModelSpec,
    overrides: Mapping[str, str] | None = None,
) -> tuple[resolved.ResolvedModel | None, list[Diagnostic]]:
    """The resolved model (None if anything is wrong) and every finding."""
    checker = Checker(document, overrides)
    return checker.model(model), checker.found
