"""How the builder evaluates its kernels: the one switch between inline and mapped evaluation,
and the model's numbers as kernel data.

Every quantity of equations.system is written once, as kernels (equations.row_kernels,
body_kernels, force_kernels: one SX Function per kind of constraint row, body term and force
element) called over their instances, with gathered inputs and outputs put in place by index
tables. An `Evaluation` decides what such a call is (numerics.instances):

- inline: SX; each instance's kernel expanded into one graph per function, built with common
  subexpressions merged (a body's rotation, read by all of its rows, computed once): the
  interpreted bundle, and the compiled one where unrolled C is smaller or faster (WHERE_INLINE);
- mapped: MX; one call of each kernel mapped over its instances: compiled C whose size does
  not grow with the model.

The model data: an IR whose numbers are symbols (model.parametric.split, with `data` its
column d) gives every function the trailing input d; the kernels read their data as
expressions of d (inline: the SX themselves; mapped: MX through a Function of d).
"""

from __future__ import annotations

import math
from dataclasses import field

import casadi as ca
import numpy as np

from casmech.core.records import record
from casmech.numerics import instances

# What each compiled (or interpreted) use of the builder evaluates inline, by the model's number
# of bodies: at most this many bodies inline, mapped above. (The DAE residuals of a library are
# also mapped when their unrolled SX exceeds formulations.residuals.UNROLLED_INSTRUCTIONS.)
WHERE_INLINE = {
    "interpreted": math.inf,  # CasADi's virtual machine runs SX fastest: always inline
    "library": 0,  # the compiled bundle (docs/decisions/codegen-element-residuals.md)
    "prescribed_step": 32,  # the compiled kinematics step (docs/decisions/prescribed-step.md)
    "dae_library": 4,  # the compiled DAE residuals (docs/decisions/codegen-small-dae-unrolled.md)
    "parametric": 32,  # a library over the model data (backends.parametric.MAX_BODIES)
    # the interpreted bundle's results-row terms (equations.functions.results_terms): above
    # this, built mapped and expanded, which is faster than inline at both building and
    # evaluating them (runtime.results.row_function then calls them instead of inlining them)
    "results": 64,
}
# Inline functions of at most this many bodies merge their common subexpressions (a frame or a
# kernel's term shared by several rows): fewer instructions per call, for a merge that costs
# about what building the graph does (docs/decisions/one-builder.md).
MERGED_BODIES = 64


def is_inline(use: str, n_bodies: int) -> bool:
    """Whether `use` (a key of WHERE_INLINE) evaluates a model of n_bodies inline."""
    return n_bodies <= WHERE_INLINE[use]


@record
class Evaluation:
    """Inline (SX) or mapped (MX) evaluation of kernels; `data`: the symbols of a symbolic IR's
    numbers (model.parametric.split), None for a numeric IR."""

    inline: bool
    data: ca.SX | None = None
    merged: bool = False  # inline functions with common subexpressions merged (cse)
    # the model data as the functions' input: data itself (inline), an MX symbol (mapped)
    input: object = field(default=None, compare=False)
    _converted: dict = field(default_factory=dict, compare=False, repr=False)
    _kept: dict = field(default_factory=dict, compare=False, repr=False)

    def kept(self, owner, name: str, make):
        """make(), once per owner (an IR) and name for this evaluation (what several
        functions read: a model's row groups)."""
        key = (id(owner), name)
        if key not in self._kept or self._kept[key][0] is not owner:
            self._kept[key] = (owner, make())
        return self._kept[key][1]

    @staticmethod
    def of(inline: bool, data: ca.SX | None = None, n_bodies: int = 0) -> Evaluation:
        """The evaluation of a model of n_bodies (inline: merged up to MERGED_BODIES)."""
        symbol = None if data is None else data if inline else ca.MX.sym("d", data.numel())
        return Evaluation(inline, data, inline and n_bodies <= MERGED_BODIES, symbol)

    @property
    def sym(self):
        """ca.SX or ca.MX: the functions' symbols."""
        return ca.SX if self.inline else ca.MX

    @property
    def symbolic(self) -> bool:
        return self.data is not None

    def call(self, kernel: ca.Function, count: int, *args, map_with=instances.mapped) -> list:
        """The kernel over `count` instances (numerics.instances.over)."""
        return instances.over(kernel, count, args, self.inline, map_with)

    def constant(self, value):
        """Model data as an argument: a DM for numbers; an expression of the IR's symbols as SX
        (inline) or as the same expression of the MX input d (mapped)."""
        if not isinstance(value, ca.SX):
            return ca.DM(value)
        if value.is_constant():
            return ca.DM(value)
        if self.inline:
            return value
        key = id(value)
        if key not in self._converted:
            of = ca.Function("data", [self.data], [value])
            self._converted[key] = (value, of.call([self.input], True, False)[0])
        return self._converted[key][1]

    def apply(self, symbols: list, outputs: list, args: list) -> list:
        """SX `outputs` of `symbols` (and of the model data) at `args`, inlined: no call node
        (a driver's f(t), a force's value)."""
        if self.inline:  # (the model data's symbols stay as they are)
            return ca.substitute(list(outputs), list(symbols), [ca.SX(a) for a in args])
        extra = [self.data] if self.symbolic else []
        of = ca.Function("inlined", [*symbols, *extra], outputs)
        return of.call([*args, *([self.input] if extra else [])], True, False)

    def function(self, name: str, inputs: dict, outputs: dict, merged: bool | None = None
                 ) -> ca.Function:
        """A named Function of the bundle: the model data last (when symbolic); inline with its
        common subexpressions merged as `merged` says (None: as the evaluation is), mapped with
        one derivative direction per kernel call."""
        if self.symbolic:
            inputs = inputs | {"d": self.input}
        options = {"cse": self.merged if merged is None else merged} if self.inline else \
            {"max_num_dir": instances.MAX_DIRECTIONS}
        return ca.Function(name, list(inputs.values()), list(outputs.values()), list(inputs),
                           list(outputs), options)


# --- numbers or symbols ------------------------------------------------------------------------

def entries(value, order: str = "C") -> list:
    """The scalars of a vector or matrix of the IR (numbers, or SX entries of the model data),
    flattened in `order` ("F": column by column)."""
    if isinstance(value, ca.SX):
        matrix = ca.densify(value)
        if order == "F":
            return [matrix[k] for k in range(matrix.numel())]
        return [matrix[i, j] for i in range(matrix.size1()) for j in range(matrix.size2())]
    return list(np.asarray(value, float).ravel(order=order))


def is_zero(entry) -> bool:
    """A structural zero of the model data (a symbol is a non-zero by construction)."""
    if isinstance(entry, ca.SX):
        return entry.is_zero()
    return float(entry) == 0.0


def numeric(values: list) -> bool:
    return not any(isinstance(v, ca.SX) and not v.is_constant() for v in values)


def columns(pattern: ca.Sparsity, values: list[list]):
    """The (pattern x count) matrix whose column k holds values[k] on the pattern's entries:
    a DM for numbers, else SX."""
    count = len(values)
    sparsity = ca.repmat(pattern, 1, count)
    flat = [v for column in values for v in column]
    if numeric(flat):
        return ca.DM(sparsity, [float(ca.DM(v)) if isinstance(v, ca.SX) else float(v)
                                for v in flat])
    return ca.SX(sparsity, ca.vertcat(*flat) if flat else ca.SX(0, 1))


def sparse_column(pattern: tuple[bool, ...]) -> ca.Sparsity:
    """The (len(pattern) x 1) sparsity of the entries `pattern` marks non-zero."""
    nonzero = [k for k, on in enumerate(pattern) if on]
    return ca.Sparsity.triplet(len(pattern), 1, nonzero, [0] * len(nonzero))
