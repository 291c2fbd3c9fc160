"""A lowered model split into its structure and its numbers: the model data `d`.

Every number that the lowering computed from the parameters (masses, inertias, gravity, body-frame
joint points and axes, a distance's length, spring constants, the constants of drivers and force
laws, initial poses and velocities) becomes one entry of a vector of CasADi symbols `d`, in a
fixed order; what is left is the structure (which bodies, rows, force elements, kernels, the
texts of the expressions) and which numbers are zero (or round-off: ROUNDOFF): those stay
structural zeros, so the functions have the sparsity (and nearly the arithmetic) of the numeric
build. `split(ir)` returns the IR with symbols in place of the other numbers, their values and
the structure's signature: two lowerings of one file with different parameter values have the
same signature, and then the same symbolic IR, unless a value changed the structure (a repeat
count, a zero that became non-zero: an initial angle moved from 0, a joint point moved off an
axis), which a build keyed on the signature sees as a different model.

`data(ir)` is the vector alone (the numeric lowering at other values gives the values to bind to
a build made once). Indices, names, texts, sources and the analysis settings are structure.

The lowering of a model loaded with symbolic parameters (schema.load_model_text's `symbolic`)
holds traced numbers (casmech.core.traced): each is an entry of d whatever its value (it
moves with the parameters even where it is 0 at their values), and the split records its
expression, so `Split.expressions` is d as a function of the parameters' symbols (the model's
`symbols`): d(theta), differentiable by CasADi. Numbers that do not depend on them keep the
rules above (zeros and round-off are structure).
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Mapping
from dataclasses import fields, is_dataclass, replace

import casadi as ca
import numpy as np

from casmech.core import traced
from casmech.core.expressions import Expr
from casmech.core.records import record
from casmech.errors import Source
from casmech.model.ir import ModelIR, RowInfo
from casmech.schema.resolved import Analysis
from casmech.schema.tables import TableExpr

# ModelIR fields that are not part of what the system functions compute from (the file's pose
# before the joints' initial values moved it: only assembly's start, on the numeric IR)
STRUCTURE_FIELDS = frozenset({"name", "file", "text", "analysis", "parameters",
                              "reference_pose"})
# entries below this fraction of their array's largest are round-off of the lowering's rotations
# (a joint point on an axis, in a body frame: 0 or 1e-17 depending on the values): structural 0
ROUNDOFF = 1e-13
FLOAT = np.dtype(float)
# structure: recorded in the signature, never symbolic (a table's data is part of the cache key)
OPAQUE = (str, bytes, range, Source, RowInfo, Analysis, Expr, TableExpr, type(None))


class Entry(ca.SX):
    """A scalar of the model data: non-zero by construction (zeros are structure, in the
    signature), so comparing it with 0 is a fact of the structure that the compiler's Python
    may branch on (a contact's damping exponent); any other comparison stays symbolic."""

    def __eq__(self, other):
        return False if _zero(other) else ca.SX.__eq__(self, other)

    def __ne__(self, other):
        return True if _zero(other) else ca.SX.__ne__(self, other)

    __hash__ = ca.SX.__hash__


def _zero(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and value == 0


@record
class Split:
    """A lowered model split into structure and numbers: the IR over the symbols d, d's
    values and the structure's signature."""

    ir: ModelIR  # numbers replaced by entries of `symbols` (structural zeros kept)
    symbols: ca.SX  # d, the column of every symbol in `ir`, in walk order
    values: np.ndarray  # d of the lowering that was split
    signature: str  # sha256 of the structure (module docstring)
    # d as expressions of the symbolic parameters (the traced numbers' expressions; the
    # values where an entry does not depend on them)
    expressions: ca.SX | None = None
    traced: np.ndarray | None = None  # (len(d),) bool: the entries that are traced numbers

    def data_function(self, theta) -> ca.Function:
        """theta -> d: the model data as a function of the symbolic parameters (`theta`: a
        column of the model's symbols, in the order wanted)."""
        return ca.Function("model_data", [theta], [self.expressions], ["theta"], ["d"])


class _Walk:
    """One pass over an IR: collects the numbers (and, when `symbolic`, makes their symbols)."""

    def __init__(self, symbolic: bool):
        self.symbolic = symbolic
        self.values: list[float] = []
        self.symbols: list[ca.SX] = []
        self.traced: dict[int, ca.SX] = {}  # entry of d -> its expression (traced numbers)
        self.tokens: list[str] = []
        self.where: list[str] = []  # the IR path being walked ("bodies", "bar", "r0")
        self.places: list[str] = []  # the path of each token

    def token(self, text: str) -> None:
        self.tokens.append(text)
        self.places.append(".".join(self.where))

    def inside(self, name: str, value):
        """self(value) with `name` on the path."""
        self.where.append(name)
        try:
            return self(value)
        finally:
            self.where.pop()

    def number(self, value) -> object:
        expressions = None
        if isinstance(value, traced.Traced) or getattr(value, "dtype", FLOAT).kind == "O":
            value, expressions = self.traced_number(value)
        array = np.asarray(value, float)
        flat = array.ravel(order="F")
        magnitude = np.abs(flat)
        scale = magnitude.max(initial=0.0)
        finite, infinite = None, ""
        if scale < math.inf:
            nonzero = magnitude > ROUNDOFF * scale
        else:  # an infinity (a stop's absent bound) is structure
            finite = np.isfinite(flat)
            nonzero = finite & (magnitude > ROUNDOFF * magnitude[finite].max(initial=0.0))
            infinite = "".join(f"!{n}{flat[n]!r}" for n in np.flatnonzero(~finite))
        if expressions is not None:  # a traced entry is never a structural zero
            moving = expressions.ravel(order="F")
            nonzero |= np.array([e is not None for e in moving], bool)
            for k, n in enumerate(np.flatnonzero(nonzero)):
                if moving[n] is not None:
                    self.traced[len(self.values) + k] = moving[n]
        self.token(f"#{array.shape}{np.packbits(nonzero).tobytes().hex()}{infinite}")
        self.values.extend(flat[nonzero])
        if not self.symbolic:
            return value
        fixed = np.zeros(flat.size, bool) if finite is None else ~finite
        entries = []
        for keep, number, structure in zip(nonzero, flat, fixed, strict=True):
            entries.append(ca.SX.sym(f"d{len(self.symbols)}") if keep else
                           ca.SX(number if structure else 0.0))
            self.symbols += [entries[-1]] if keep else []
        if array.ndim == 0:
            return Entry(entries[0]) if nonzero[0] else float(flat[0]) if fixed[0] else 0.0
        rows, cols = (array.shape[0], 1) if array.ndim == 1 else array.shape
        return ca.reshape(ca.vertcat(*entries), rows, cols)

    @staticmethod
    def traced_number(value) -> tuple[np.ndarray, np.ndarray]:
        """(the values, an object array of the expressions of the entries that depend on the
        symbolic parameters, None elsewhere) of a traced number or array."""
        array = np.asarray(value, object)
        expressions = np.full(array.shape, None, object)
        for index, item in np.ndenumerate(array):
            if isinstance(item, traced.Traced) and not item.constant:
                expressions[index] = item.expr
        return traced.value(array).reshape(array.shape), expressions

    def __call__(self, value):
        if isinstance(value, traced.Traced):
            return self.number(value)
        if isinstance(value, bool) or isinstance(value, OPAQUE):
            self.token(repr(value) if isinstance(value, (str, bool, range)) else
                       type(value).__name__ + str(getattr(value, "text", "")))
            return value
        if isinstance(value, (float, np.floating)):
            return self.number(value)
        if isinstance(value, np.ndarray) and value.dtype.kind in "fO":
            return self.number(value)
        if isinstance(value, int):
            self.token(str(value))
            return value
        if is_dataclass(value):
            self.token(type(value).__name__)
            changed = {}
            for item in fields(value):
                if isinstance(value, ModelIR) and item.name in STRUCTURE_FIELDS:
                    continue
                self.token(item.name)
                changed[item.name] = self.inside(item.name, getattr(value, item.name))
            return replace(value, **changed) if self.symbolic else value
        if isinstance(value, Mapping):
            self.token(f"{{{len(value)}")
            out = {}
            for key, item in value.items():
                self.token(str(key))
                out[key] = self.inside(str(key), item)
            return out if self.symbolic else value
        if isinstance(value, (tuple, list)):
            self.token(f"({len(value)}")
            out = [self.inside(_label(k, item), item) for k, item in enumerate(value)]
            return type(value)(out) if self.symbolic else value
        raise TypeError(f"parametric: no rule for a {type(value).__name__} in a ModelIR")

    def signature(self) -> str:
        return hashlib.sha256("\0".join(self.tokens).encode()).hexdigest()


def _label(index: int, item) -> str:
    """An item of a sequence on a path: its name when it has one ('bar'), a primitive's joint
    and kind (3 ('pivot' dp1)), else its index."""
    name, row = getattr(item, "name", None), getattr(item, "row", None)
    if isinstance(name, str) and name:
        return f"'{name}'"
    if isinstance(row, RowInfo):
        return f"{index} ('{row.joint}' {row.kind})"
    return str(index)


def difference(a: ModelIR, b: ModelIR) -> str | None:
    """Where the structures of two lowerings first differ ("bodies.'bar'.r0: 3 non-zero
    entries, now 2"), or None when their signatures are equal."""
    walks = [_Walk(symbolic=False), _Walk(symbolic=False)]
    for walk, ir in zip(walks, (a, b), strict=True):
        walk(ir)
    first, second = walks
    for k, (x, y) in enumerate(zip(first.tokens, second.tokens, strict=False)):
        if x != y:
            place = first.places[k] or "the model"
            return f"{place}: {_describe(x)}, now {_describe(y)}"
    if len(first.tokens) != len(second.tokens):
        return f"{first.places[-1] if first.places else 'the model'}: more or fewer items"
    return None


def _describe(token: str) -> str:
    """A token of the walk in words: an array's zero pattern, or the token itself."""
    if not token.startswith("#"):
        return repr(token)
    shape, pattern = token[1:].split(")", 1)
    bits = np.unpackbits(np.frombuffer(bytes.fromhex(pattern), np.uint8))
    size = int(np.prod([int(n) for n in shape.strip("(,").split(",") if n.strip()]))
    nonzero = int(bits[:size].sum())
    return f"{nonzero} non-zero of {size} entries" if size > 1 else \
        ("non-zero" if nonzero else "zero")


def split(ir: ModelIR) -> Split:
    """The IR with its numbers as symbols, their values, the structure's signature and d as
    expressions of the symbolic parameters (module docstring)."""
    walk = _Walk(symbolic=True)
    symbolic = walk(ir)
    symbols = ca.vertcat(*walk.symbols) if walk.symbols else ca.SX(0, 1)
    values = np.array(walk.values, float)
    expressions = ca.SX(ca.DM(values)) if values.size else ca.SX(0, 1)
    for index, expression in walk.traced.items():
        expressions[index] = expression
    moving = np.zeros(values.size, bool)
    moving[list(walk.traced)] = True
    return Split(symbolic, symbols, values, walk.signature(), expressions, moving)


def data(ir: ModelIR) -> tuple[np.ndarray, str]:
    """(d, signature) of a numeric IR without building symbols."""
    walk = _Walk(symbolic=False)
    walk(ir)
    return np.array(walk.values, float), walk.signature()


DATA = "d"  # the name of the model data input, last in every function of a parametric bundle


def data_size(functions: Mapping[str, ca.Function]) -> int:
    """Entries of the model data a bundle's functions take last (0: none)."""
    phi = functions["phi"]
    return phi.size1_in(phi.n_in() - 1) if phi.name_in()[-1] == DATA else 0


def with_data(functions: Mapping[str, ca.Function], d) -> Mapping:
    """The bundle's functions called with `d` (symbols) as their model data, if they take any
    (what formulations.dae and formulations.prescribed build over)."""
    if not data_size(functions):
        return functions
    return {name: (lambda *args, f=f: f(*args, d)) for name, f in functions.items()}
