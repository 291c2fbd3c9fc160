"""A model's system functions moved to other parameter values: what
casmech.api.CompiledModel.set does, imported only when it is called.

`moved(functions, model, values)` loads the model's text again with the values as `--set`
overrides on top of those it was loaded with (numbers, or texts with units: "30 deg"), so a
value is checked as the file's would be (a located ModelError), and then:

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
from pathlib import Path

from casmech import backends
from casmech.backends.load import mode_of
from casmech.backends.manifest import MANIFEST
from casmech.backends.parametric import MAX_BODIES
from casmech.backends.parametric import load as bind_library
from casmech.equations.functions import SystemFunctions
from casmech.errors import UsageError
from casmech.model import parametric
from casmech.model.lower import lower
from casmech.schema import load_model_text
from casmech.schema.loader import load_document
from casmech.schema.resolved import ResolvedModel


def moved(functions: SystemFunctions, model: ResolvedModel,
          values: Mapping[str, float | str]) -> tuple[SystemFunctions, ResolvedModel]:
    """(the bundle, the model) at `values` over `model`'s, from `functions` compiled from
    `model` (module docstring)."""
    texts = {str(name): override_text(name, value) for name, value in values.items()}
    new_model = reload(model, texts)
    bound = functions.parametric
    folder, signature = (bound.folder, bound.signature) if bound else (None, None)
    if folder is not None and (Path(folder) / MANIFEST).is_file():
        ir = lower(new_model)
        data, new_signature = parametric.data(ir)
        if new_signature != signature:
            raise structure_error(model, texts, signature)
        return bind_library(Path(folder), ir, data, signature), new_model
    if folder is None and mode_of(functions) == "compiled":
        warnings.warn(f"{new_model.name}: its compiled library holds its values (more than "
                      f"{MAX_BODIES} bodies, or no parameters), so set builds another one; "
                      "compile with mode='interpreted' to change values without a build",
                      stacklevel=3)
        return backends.compile(new_model, "compiled"), new_model
    # interpreted; or a parametric library gone from the cache since (built again)
    return backends.compile(new_model, "compiled" if folder else "interpreted"), new_model


def library(functions: SystemFunctions) -> Path | None:
    """The folder of the parametric library a bundle is bound to (None: none)."""
    return functions.parametric.folder if functions.parametric else None


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
