"""What casmech.compile returns: a model's system functions at its parameter values, with
`set` to move them to other values.

    pendulum = casmech.compile(casmech.load("models/estimate_pendulum.yaml"), "compiled")
    heavier = pendulum.set(m=2)              # a new CompiledModel; `pendulum` is unchanged
    casmech.analyze(heavier)

`set(name=value, ...)` (or a mapping, for names such as `front_left.m1`) loads the model's text
again with the values as `--set` overrides on top of those it was loaded with (numbers, or
texts with units: "30 deg"), so a value is checked as the file's would be (a located
ModelError), and then:

- a bundle bound to a parametric library (backends.parametric: the model data d as an input,
  the build keyed on the structure) is bound to the new d, the numeric lowering at the new
  values (model.parametric.data): nothing is generated or built, the library is shared by
  both bundles. A value that changes the structure (a repeat count, a zero that becomes
  non-zero: model.parametric) is a UsageError naming the parameter and what changed;
- an interpreted bundle is built again at the new values (equations.functions' functions are
  built when first used);
- a compiled library with the values baked in (models over backends.parametric.MAX_BODIES
  bodies) is compiled again through the cache, a build per set of values, with a warning.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from types import MappingProxyType

import numpy as np

from casmech import backends
from casmech.backends.load import mode_of
from casmech.backends.manifest import MANIFEST
from casmech.backends.parametric import LIBRARY_FOLDER, MAX_BODIES, SIGNATURE
from casmech.backends.parametric import load as bind_library
from casmech.equations import checks
from casmech.equations.functions import SystemFunctions
from casmech.errors import UsageError
from casmech.model import parametric
from casmech.model.lower import lower
from casmech.schema import load_model_text
from casmech.schema.loader import load_document
from casmech.schema.resolved import ResolvedModel

DOF = "dof"  # the key of the degrees of freedom in a bundle's `derived`


@dataclass(frozen=True, repr=False)
class CompiledModel(SystemFunctions):
    """The system functions of `model` (a SystemFunctions: casmech.analyze takes it), compiled
    in `mode`, and `set` (module docstring)."""

    model: ResolvedModel | None = field(default=None, compare=False)
    mode: str = "interpreted"  # the mode asked of casmech.compile

    @property
    def parameters(self) -> Mapping[str, float]:
        """The model's parameter values (read-only)."""
        return MappingProxyType(dict(self.model.parameters) if self.model else {})

    @property
    def dof(self) -> int:
        """Degrees of freedom: coordinates less the rank of phi_q at the file's pose (as
        `casmech check` counts them; computed once)."""
        if DOF not in self.derived:
            bodies = self.ir.bodies
            q = np.concatenate([b.r0 for b in bodies] + [b.p0 for b in bodies] + [np.zeros(0)])
            self.derived[DOF] = checks.structure(self, 0.0, q).dof
        return self.derived[DOF]

    @property
    def library(self) -> Path | None:
        """The folder of the parametric library the functions are bound to (None: none)."""
        return self.derived.get(LIBRARY_FOLDER)

    def set(self, values: Mapping[str, float | str] | None = None, /,
            **named: float | str) -> CompiledModel:
        """The model at other parameter values, as a new CompiledModel (module docstring):
        `values` and `named` map parameter names to numbers or texts ("30 deg")."""
        given = {**dict(values or {}), **named}
        if not given:
            return self
        if self.model is None:
            raise UsageError("set needs the model these functions were compiled from: use "
                             "casmech.compile(model)")
        texts = {str(name): override_text(name, value) for name, value in given.items()}
        model = reload(self.model, texts)
        folder, signature = self.derived.get(LIBRARY_FOLDER), self.derived.get(SIGNATURE)
        if folder is not None and (Path(folder) / MANIFEST).is_file():
            ir = lower(model)
            data, new_signature = parametric.data(ir)
            if new_signature != signature:
                raise structure_error(self.model, texts, signature)
            return wrap(bind_library(Path(folder), ir, data, signature), model, self.mode)
        if folder is None and mode_of(self) == "compiled":
            warnings.warn(f"{model.name}: its compiled library holds its values (more than "
                          f"{MAX_BODIES} bodies, or no parameters), so set builds another one; "
                          "compile with mode='interpreted' to change values without a build",
                          stacklevel=2)
            return wrap(backends.compile(model, "compiled"), model, self.mode)
        # interpreted; or a parametric library gone from the cache since (built again)
        return wrap(backends.compile(model, "compiled" if folder else "interpreted"), model,
                    self.mode)

    def __repr__(self) -> str:
        shown = ", ".join(f"{name}={value:.6g}" for name, value in
                          list(self.parameters.items())[:6])
        more = len(self.parameters) - 6
        shown += f", ... ({more} more)" if more > 0 else ""
        how = mode_of(self) + (", parametric library" if self.library else "")
        name = self.model.name if self.model else self.ir.name
        bodies = f"{self.n_bodies} {'body' if self.n_bodies == 1 else 'bodies'}"
        joints = f"{len(self.joints)} joint{'' if len(self.joints) == 1 else 's'}"
        return (f"CompiledModel('{name}': {bodies}, {joints}, {self.dof} DOF; {how}; "
                f"parameters: {shown or 'none'})")


def wrap(functions: SystemFunctions, model: ResolvedModel, mode: str) -> CompiledModel:
    """The bundle as a CompiledModel (its functions and what analyses derived, shared)."""
    if isinstance(functions, CompiledModel):
        return functions
    return CompiledModel(**{f.name: getattr(functions, f.name) for f in fields(SystemFunctions)},
                         model=model, mode=mode)


def compiled_model(model: ResolvedModel, mode: str = "interpreted") -> CompiledModel:
    """backends.compile(model, mode) as a CompiledModel."""
    return wrap(backends.compile(model, mode), model, mode)


def override_text(name: str, value) -> str:
    """A value of `set` as the `--set` text the schema reads: a number exactly (repr
    round-trips a float), a text as written."""
    if isinstance(value, str):
        return value
    if isinstance(value, bool):
        raise UsageError(f"set: parameter '{name}' takes a number or a text, got {value!r}")
    try:
        return repr(float(value))
    except (TypeError, ValueError):
        raise UsageError(f"set: parameter '{name}' takes a number or a text such as "
                         f"'30 deg', got {type(value).__name__} {value!r}") from None


def reload(model: ResolvedModel, texts: Mapping[str, str]) -> ResolvedModel:
    """The model loaded again from its text with `texts` over its own overrides."""
    return load_model_text(model.text, model.file, {**model.overrides, **texts})


def structure_error(model: ResolvedModel, texts: Mapping[str, str],
                    signature: str | None) -> UsageError:
    """The parameters among `texts` whose value alone changes the structure the library was
    built for (all of them when only together they do), located at the first one's key."""
    culprits = [name for name, text in texts.items()
                if parametric.data(lower(reload(model, {name: text})))[1] != signature]
    culprits = culprits or list(texts)
    changed = parametric.difference(lower(model),
                                    lower(reload(model, {n: texts[n] for n in culprits})))
    values = ", ".join(f"'{name}' = {texts[name]}" for name in culprits)
    document = load_document(model.text, model.file)
    written = document.data.get("parameters") or {}
    where = (document.locate_key(("parameters", culprits[0])) if culprits[0] in written
             else model.file)
    plural = "s" if len(culprits) > 1 else ""
    overrides = {**model.overrides, **texts}
    built = ", ".join(f"{name} = {model.parameters.get(name, '?')}" for name in culprits)
    return UsageError(
        f"{where}: parameter{plural} {values} change{'' if plural else 's'} the structure of "
        f"the compiled model ({changed}), which its library, built for the structure at "
        f"{built}, cannot take\n  hint: casmech.compile(casmech.load('{model.file}', "
        f"overrides={overrides!r}), 'compiled') builds a library for this structure; "
        "mode='interpreted' takes any value")
