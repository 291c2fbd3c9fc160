"""d(theta): the model data of model.parametric as a CasADi Function of file parameters,
exact at every theta (what estimation needs to fit a length, a joint point or an axis angle).

Its value at theta is the numeric lowering of the model re-loaded with those parameter values
(every other top-level parameter kept at the value it has, unless computed from them); its
Jacobian is lowering.derivative at that theta (sixth-order central differences of the
lowering, error-estimated). Both are CasADi callbacks, so they sit in MX graphs (IPOPT's NLP)
but not in SX or generated C; each evaluation is a few loads of the YAML, so one theta is
lowered once and kept (`_Cache`).

A theta at which the model changes its structure (lowering.py's signature) or becomes invalid
has no data in this build: the callbacks return NaN there (IPOPT then shortens its step) and
`failure()` holds the located usage error, which the caller raises if the solver stops.
"""

from __future__ import annotations

from collections.abc import Sequence

import casadi as ca
import numpy as np

from casmech.errors import ModelError, UsageError
from casmech.model import parametric
from casmech.model.lower import lower
from casmech.optimal import lowering
from casmech.runtime.memo import kept
from casmech.schema.resolved import ResolvedModel

KEPT = 8  # theta values whose model, data and Jacobian are kept


class _Outside(Exception):
    """theta has no data in this structure (the _Cache's `failure` says why)."""


class _Cache:
    """The model, d and dd/dtheta at recent theta values."""

    def __init__(self, model: ResolvedModel, names: Sequence[str]):
        self.model, self.names = model, tuple(names)
        self.lowering = lowering.Lowering(model)
        self.signature = parametric.data(lower(model))[1]
        self.models: dict[tuple, ResolvedModel] = {}
        self.data: dict[tuple, np.ndarray] = {}
        self.jacobians: dict[tuple, np.ndarray] = {}
        self.failure: UsageError | None = None

    def _key(self, theta) -> tuple:
        return tuple(float(v) for v in np.asarray(theta, float).ravel())

    def _located(self, key: tuple, what: str, detail: str) -> UsageError:
        """'parameter N <what> at N = v, ... (<detail>)', located at the first name."""
        at = ", ".join(f"{n} = {v:.9g}" for n, v in zip(self.names, key, strict=True))
        return lowering.located(self.model, self.names[0], f"{what} at {at} ({detail})")

    def _fail(self, error: UsageError):
        self.failure = error
        raise _Outside from None

    def model_at(self, key: tuple) -> ResolvedModel:
        return kept(self.models, key, lambda: self._reloaded(key), KEPT)

    def _reloaded(self, key: tuple) -> ResolvedModel:
        try:
            return self.lowering.reloaded(dict(zip(self.names, key, strict=True)))
        except ModelError as error:
            self._fail(self._located(key, "makes the model invalid",
                                     error.diagnostics[0].format()))

    def values(self, theta) -> np.ndarray:
        key = self._key(theta)
        return kept(self.data, key, lambda: self._values(key), KEPT)

    def _values(self, key: tuple) -> np.ndarray:
        ir = lower(self.model_at(key))
        values, signature = parametric.data(ir)
        if signature != self.signature:
            change = parametric.difference(lower(self.model), ir)
            self._fail(self._located(key, "changes the model's structure", change))
        return values

    def jacobian(self, theta) -> np.ndarray:
        key = self._key(theta)
        return kept(self.jacobians, key, lambda: self._jacobian(key), KEPT)

    def _jacobian(self, key: tuple) -> np.ndarray:
        try:
            return lowering.derivative(self.model_at(key), self.names).jacobian
        except UsageError as error:
            self._fail(error)


class _Jacobian(ca.Callback):
    """(theta, d) -> dd/dtheta at theta (the derivative a ModelData callback declares)."""

    def __init__(self, cache: _Cache, size: int):
        ca.Callback.__init__(self)
        self.cache, self.size = cache, size
        self.construct("model_data_jacobian", {})

    def get_n_in(self):
        return 2

    def get_n_out(self):
        return 1

    def get_sparsity_in(self, index):
        return ca.Sparsity.dense(len(self.cache.names) if index == 0 else self.size, 1)

    def get_sparsity_out(self, index):
        return ca.Sparsity.dense(self.size, len(self.cache.names))

    def eval(self, arg):
        try:
            return [ca.DM(self.cache.jacobian(np.array(arg[0]).ravel()))]
        except _Outside:
            return [ca.DM.nan(self.size, len(self.cache.names))]


class ModelData(ca.Callback):
    """theta -> d: the model data at file parameter values `names` (module docstring)."""

    def __init__(self, model: ResolvedModel, names: Sequence[str]):
        ca.Callback.__init__(self)
        self.cache = _Cache(model, names)
        self.size = self.cache.values([float(model.parameters[n]) for n in names]).size
        self.jacobian_callback = None  # kept alive as long as this callback
        self.construct("model_data", {})

    def failure(self) -> UsageError | None:
        """The usage error that stopped an evaluation (a theta outside the structure)."""
        return self.cache.failure

    def get_n_in(self):
        return 1

    def get_n_out(self):
        return 1

    def get_sparsity_in(self, index):
        return ca.Sparsity.dense(len(self.cache.names), 1)

    def get_sparsity_out(self, index):
        return ca.Sparsity.dense(self.size, 1)

    def eval(self, arg):
        try:
            return [ca.DM(self.cache.values(np.array(arg[0]).ravel()))]
        except _Outside:
            return [ca.DM.nan(self.size, 1)]

    def has_jacobian(self):
        return True

    def get_jacobian(self, name, inames, onames, options):
        self.jacobian_callback = _Jacobian(self.cache, self.size)
        theta, d = (ca.MX.sym(n, self.get_sparsity_in(0) if k == 0 else
                              self.get_sparsity_out(0)) for k, n in enumerate(inames))
        return ca.Function(name, [theta, d], [self.jacobian_callback(theta, d)], inames, onames)
