"""Backends: the system functions of a model evaluated interpreted (CasADi SX functions) or
compiled (C generated from the same functions, built, cached and loaded: backends.codegen).
A backend defines no physics; both give the same functions (names, inputs, outputs,
sparsity). This module is light: code generation is imported only when a model is compiled.
"""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING

from casmech.equations.functions import SystemFunctions, build_functions
from casmech.errors import AnalysisError, UsageError
from casmech.model.lower import lower
from casmech.schema.resolved import ResolvedModel

if TYPE_CHECKING:
    from casmech.backends.handover import Handover

COMPILE_MODES = ("interpreted", "compiled", "auto")


def compile(model: ResolvedModel, mode: str = "auto") -> SystemFunctions:  # noqa: A001
    """Build the named CasADi functions of a model. mode: "interpreted" (SX functions),
    "compiled" (C generated, built with the C compiler and loaded; cached by model content in
    $CASMECH_CACHE_DIR, default ~/.cache/casmech) or "auto", the default (whichever runs sooner
    end to end, codegen.auto_mode: compiled when the library is cached or the model is big,
    else interpreted while it is built behind for the next call; interpreted with one warning
    without a C compiler). Both bundles have the same functions."""
    return compile_handing_over(model, mode)[0]


def compile_handing_over(model: ResolvedModel, mode: str = "auto"
                         ) -> tuple[SystemFunctions, Handover | None]:
    """(compile's bundle, its handover): for an auto miss run interpreted while this process
    builds the library behind, the backends.handover.Handover that gives the compiled bundle
    once the build has published it; else None."""
    if mode not in COMPILE_MODES:
        raise UsageError(f"mode '{mode}' is not one of {', '.join(COMPILE_MODES)}")
    if mode == "interpreted":  # before importing code generation, which this path never uses
        return build_functions(lower(model)), None
    from casmech.backends import codegen

    if mode == "auto" and not codegen.available():
        warnings.warn("no C compiler found (gcc, or $CC): casmech runs interpreted CasADi "
                      "functions, which is slower; install gcc to compile models", stacklevel=3)
        return build_functions(lower(model)), None
    if mode == "auto":
        chosen, building = codegen.auto_choice(model, background=True)
        if chosen == "interpreted":
            from casmech.backends import handover

            return build_functions(lower(model)), handover.pending(model, building)
    try:
        return codegen.compiled(model), None
    except (AnalysisError, UsageError) as error:  # the compiler failed; no writable cache
        if mode == "compiled":
            raise
        warnings.warn(f"{str(error).splitlines()[0]}; casmech runs interpreted CasADi "
                      "functions instead", stacklevel=3)
        return build_functions(lower(model)), None
