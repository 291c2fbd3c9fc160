"""The joints' `initial:` values held while assembly closes the loops (docs/format.md#initial-
state).

model/initial.py poses the bodies along the spanning tree, so a tree meets every value at
once. Where loops close (cut joints), runtime/assembly.py assembles with the values held:
it runs its own algorithm (continuation from the file's pose, Newton, the closest point to the
posed state; then the velocities) on a bundle whose constraint rows are the joint rows, the
held rows (equations/initial_rows.py) and the normalization rows, in that order, so that
equations.checks blames a dependency on the later, held rows. Here: those bundles (`Holds`)
and the findings they make, as located model errors at the `initial:` keys:

- E504 (overdetermined): a held row that depends on the joint rows and the held rows before
  it (at the file's pose for positions, at the assembled pose for rates): a value that the
  mechanism and the other values fix already, consistent or not;
- E503 (cannot be met): assembly does not converge with the values held (a loop that cannot
  close with them), naming the held joints and the joints with the largest residuals.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import replace

import casadi as ca
import numpy as np

from casmech.core.records import record
from casmech.equations.checks import structure
from casmech.equations.functions import SystemFunctions
from casmech.equations.symbols import Coordinates
from casmech.errors import AnalysisError, Diagnostic, ModelError
from casmech.model.ir import RowInfo
from casmech.runtime.workspace import Workspace, of


class _Overlay(Mapping):
    """A bundle's functions with some replaced (the others built on use, as they are)."""

    def __init__(self, base, replaced: dict):
        self.base, self.replaced = base, replaced

    def __getitem__(self, name: str) -> ca.Function:
        return self.replaced[name] if name in self.replaced else self.base[name]

    def __iter__(self) -> Iterator[str]:
        yield from dict.fromkeys([*self.replaced, *self.base])

    def __len__(self) -> int:
        return sum(1 for _ in self)


def _symbols(functions: SystemFunctions):
    sx = all(functions[name].is_a("SXFunction") for name in ("phi", "phi_q", "nu"))
    return ca.SX if sx else ca.MX


def _insert(stack, held, joint_rows: int):
    """The joint rows of `stack`, then `held`, then the normalization rows."""
    return ca.vertcat(stack[:joint_rows, :], held, stack[joint_rows:, :])


def _positions(functions: SystemFunctions, joint_rows: int) -> tuple[SystemFunctions, int]:
    """The bundle with the position rows held; the number of held rows."""
    from casmech.equations import initial_rows

    x = Coordinates.create(functions.n_bodies)
    s = ca.SX.sym("s")
    held = initial_rows.positions(functions.ir, x, s)
    values = x.ground_fixed(held.values)
    rows_of = ca.Function("held", [x.q, s], [values, ca.jacobian(values, x.q)])
    sym = _symbols(functions)
    t, q, scale = sym.sym("t"), sym.sym("q", functions.n_coordinates), sym.sym("s")
    h1, j1 = rows_of(q, 1.0)
    hs, js = rows_of(q, scale)
    base = functions.functions
    phi, phi_q = base["phi"](t, q), base["phi_q"](t, q)
    phi_s, phi_q_s = base["phi_scaled"](t, q, scale)
    replaced = {
        "phi": ca.Function("phi", [t, q], [_insert(phi, h1, joint_rows)]),
        "phi_q": ca.Function("phi_q", [t, q], [_insert(phi_q, j1, joint_rows)]),
        "phi_scaled": ca.Function("phi_scaled", [t, q, scale],
                                  [_insert(phi_s, hs, joint_rows),
                                   _insert(phi_q_s, js, joint_rows)]),
    }
    return _overlay(functions, replaced, held.rows, joint_rows), len(held.rows)


def _velocities(functions: SystemFunctions, joint_rows: int) -> SystemFunctions:
    """The bundle with the rate rows held: [Phi_q; J] q_dot = [nu; targets]."""
    from casmech.equations import initial_rows

    x = Coordinates.create(functions.n_bodies)
    held = initial_rows.rates(functions.ir, x)
    jacobian = x.ground_fixed(ca.jacobian(held.values, x.q_dot))
    rows_of = ca.Function("rates", [x.q], [jacobian, held.targets])
    sym = _symbols(functions)
    t, q = sym.sym("t"), sym.sym("q", functions.n_coordinates)
    jac, targets = rows_of(q)
    base = functions.functions
    replaced = {
        "phi_q": ca.Function("phi_q", [t, q], [_insert(base["phi_q"](t, q), jac, joint_rows)]),
        "nu": ca.Function("nu", [t, q], [_insert(base["nu"](t, q), targets, joint_rows)]),
    }
    return _overlay(functions, replaced, held.rows, joint_rows)


def _overlay(functions: SystemFunctions, replaced: dict, held: tuple[RowInfo, ...],
             joint_rows: int) -> SystemFunctions:
    rows = (*functions.rows[:joint_rows], *held, *functions.rows[joint_rows:])
    return replace(functions, functions=_Overlay(functions.functions, replaced), rows=rows)


@record(frozen=False)
class Holds:
    """The bundles with the values held, and what assembly needs besides."""

    positions: SystemFunctions
    velocities: SystemFunctions
    reference: np.ndarray  # the file's pose (continuation starts there)
    span: float  # the largest held coordinate (continuation's length)
    n_positions: int

    def check_independent(self, bundle: SystemFunctions, t: float, q: np.ndarray,
                          what: str) -> None:
        """E504 for every held row that depends on the rows before it at q."""
        report = structure(bundle, t, q)
        held = [row for row in report.redundant if row.kind == "initial"]
        if held:
            raise ModelError([_diagnostic(
                "E504", row, f"{row.label}: overdetermined: the joints and the initial "
                f"values before it fix this {what} already",
                "give as many values as the mechanism has degrees of freedom (a loop's "
                "joints move together: give one of them)", bundle.ir.joints)
                for row in _unique(held)])

    def unmet(self, error: AnalysisError) -> ModelError:
        """E503 for the held values when assembly failed with them held."""
        rows = _unique(row for row in self.positions.rows if row.kind == "initial")
        worst = ", ".join(f"'{name}'" for name, _, _ in error.context.joints)
        return ModelError([_diagnostic(
            "E503", row, f"{row.label}: cannot be met: the loops do not close with the "
            f"initial values held ({error.context.cause.rstrip(':')} {worst})",
            "a value outside the mechanism's range of motion, or values that contradict "
            "each other", self.positions.ir.joints) for row in rows])


def _unique(rows) -> list[RowInfo]:
    """One row per (joint, label): a rotation's three rows are one value."""
    return list({(row.joint, row.label): row for row in rows}.values())


def _diagnostic(code: str, row: RowInfo, message: str, hint: str, joints) -> Diagnostic:
    """At the `initial:` key the row holds (path joints[k].initial.<key>, k in file order)."""
    key = row.label.split("initial ", 1)[1].split(" =", 1)[0]
    index = next(k for k, joint in enumerate(joints) if joint.name == row.joint)
    return Diagnostic(code, f"joints[{index}].initial.{key}", message, row.source, hint=hint)


def holds(functions: SystemFunctions, workspace: Workspace | None = None) -> Holds | None:
    """The Holds of a bundle whose joints have `initial:` values (built once per workspace),
    else None."""
    ir = functions.ir
    if ir.reference_pose is None and not any(joint.initial for joint in ir.joints):
        return None

    def build() -> Holds:
        from casmech.equations import initial_rows

        joint_rows = functions.n_joint_rows
        positions, count = _positions(functions, joint_rows)
        reference = (np.asarray(ir.reference_pose, float) if ir.reference_pose is not None
                     else np.concatenate([*(b.r0 for b in ir.bodies),
                                          *(b.p0 for b in ir.bodies)]))
        return Holds(positions, _velocities(functions, joint_rows), reference,
                     initial_rows.span(ir), count)

    return of(functions, workspace).one("initial_holds", build)
