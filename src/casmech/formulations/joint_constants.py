"""The numbers of the joint formulation that depend on the model alone (joint frames and their
quaternions, each body's spatial inertia in its reference frame, the constant transforms between
frames), as the build of formulations/joint_system.py uses them.

A numeric build (a lowered IR) gets them as casadi.DM constants (one per value object, so a
frame used by several recursions is converted once), folded into the functions' graphs. A
parametric build (model.parametric.split's IR, numbers as symbols of the model data d) gets
each entry that is not structurally zero as a new symbol; `data()` is the function
d -> [d; those entries] that computes them once per parameter value, and the joint functions
take its output as their trailing input "d" (so a frame's rotation or a transformed inertia is
not recomputed at every evaluation of the ODE).
"""

from __future__ import annotations

import casadi as ca

from casmech.core.quaternions import from_matrix

DATA = "d"  # the trailing input of a parametric build's functions


class Constants:
    """The hoisting of model-only quantities (module docstring); `data` the model data's
    symbols (None: a numeric build)."""

    def __init__(self, data: ca.SX | None = None):
        self.data = data
        self.expressions: list[ca.SX] = []
        self.symbols: list[ca.SX] = []
        self._seen: dict[tuple[str, int], tuple[object, ca.SX]] = {}  # (kind, id) -> ...

    @property
    def symbolic(self) -> bool:
        return self.data is not None

    def __call__(self, value):
        """`value` (numbers, or SX of the model data alone) as the build uses it."""
        if not self.symbolic:
            return self.once("value", value, _numeric)
        return self.once("value", value, self._hoisted)

    def raw(self, value):
        """A number of the IR as a matrix for arithmetic that `self` then hoists: a casadi.DM
        (a numeric build computes its constants in DM, folded into the graphs), or SX."""
        return ca.DM(value) if not self.symbolic else ca.SX(value)

    def once(self, kind: str, value, make):
        """make(value), once per value object (a frame used by several recursions)."""
        seen = self._seen.get((kind, id(value)))
        if seen is None or seen[0] is not value:
            seen = self._seen[kind, id(value)] = (value, make(value))
        return seen[1]

    def _hoisted(self, value) -> ca.SX:
        matrix = ca.SX(value) if isinstance(value, ca.SX) else ca.SX(ca.DM(value))
        hoisted = ca.SX.zeros(matrix.shape)
        for k in range(matrix.numel()):
            entry = matrix[k]
            if entry.is_constant():  # a structural zero, a number of the structure
                hoisted[k] = entry
                continue
            symbol = ca.SX.sym(f"c{len(self.symbols)}")
            self.symbols.append(symbol)
            self.expressions.append(entry)
            hoisted[k] = symbol
        return hoisted

    def quaternion(self, rotation):
        """The unit quaternion (e0 >= 0) of a constant rotation matrix (quaternions.from_matrix:
        Shepperd's method; in a parametric build in SX, its branch chosen where joint_data is
        evaluated, by the values)."""
        if not self.symbolic:
            return self.once("quaternion", rotation, lambda r: ca.DM(from_matrix(r)))
        return self.once("quaternion", rotation, lambda r: self(shepperd(ca.SX(r))))

    @property
    def inputs(self) -> ca.SX:
        """The trailing input of the parametric build's functions: [d; hoisted symbols]."""
        return ca.vertcat(self.data, *self.symbols)

    def function(self) -> ca.Function:
        """d -> the trailing input's values (`inputs`)."""
        return ca.Function("joint_data", [self.data], [ca.vertcat(self.data, *self.expressions)],
                           ["model_data"], [DATA])


def _numeric(value) -> ca.DM:
    return ca.DM(ca.evalf(value)) if isinstance(value, ca.SX) else ca.DM(value)


def shepperd(r: ca.SX) -> ca.SX:
    """quaternions.from_matrix in SX: every candidate computed, the largest one's branch taken
    (casadi's if_else discards the others' NaN)."""
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    half = 0.5 * ca.sqrt(1 + trace)
    best = ca.vertcat(half, (r[2, 1] - r[1, 2]) / (4 * half), (r[0, 2] - r[2, 0]) / (4 * half),
                      (r[1, 0] - r[0, 1]) / (4 * half))
    largest = trace
    for i in range(3):
        j, m = (i + 1) % 3, (i + 2) % 3
        component = 0.5 * ca.sqrt(1 + 2 * r[i, i] - trace)
        s = 4 * component
        q = [None] * 4
        q[1 + i], q[0] = component, (r[m, j] - r[j, m]) / s
        q[1 + j], q[1 + m] = (r[j, i] + r[i, j]) / s, (r[m, i] + r[i, m]) / s
        better = r[i, i] > largest
        best = ca.if_else(better, ca.vertcat(*q), best)
        largest = ca.if_else(better, r[i, i], largest)
    best = best / ca.norm_2(best)
    return ca.if_else(best[0] >= 0, best, -best)
