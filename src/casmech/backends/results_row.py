"""A compiled bundle's results row compiled too, cached under the bundle's library key.

runtime.results maps the results row (equations.results_row.row_function) over a run's rows.
Over a compiled bundle that row is an MX graph calling the library's results terms, with the
readings (the joint states and outputs) as SX evaluated by CasADi, and a process would build
it, load the terms' library and build the readings' SX every time it writes results. Here the
same graph, over the terms as their library builds them (equations.results_row.mapped_bundle:
the same functions, each operation the same) and the same readings, is compiled once by
backends.library.compile_keyed, keyed by the bundle's library key (the model, the versions,
casmech's sources and the bundle's toolchain) and the default toolchain, and loaded from the
cache afterwards: a warm run loads one function.
"""

from __future__ import annotations

import warnings

import casadi as ca

from casmech.backends.build import Toolchain, available
from casmech.backends.library import compile_keyed
from casmech.equations import readings
from casmech.equations.functions import SystemFunctions
from casmech.errors import AnalysisError

NAME = "results_row"


def applies(functions: SystemFunctions) -> bool:
    """Whether the bundle is a compiled mapped library's (backends.load: its library key, no
    model data bound)."""
    return functions.library_key is not None and functions.data is None and \
        functions.parametric is None


def compiled(functions: SystemFunctions) -> ca.Function | None:
    """The bundle's results row from its compiled library (module docstring), built when the
    cache holds none; None when it does not apply, without a C compiler to build it, or when
    the build failed (with a warning)."""
    if not applies(functions):
        return None
    toolchain = Toolchain()
    if not available(toolchain):
        return None
    content = {"kind": "results row", "bundle": functions.library_key}

    def make():
        from casmech.equations.results_row import mapped_bundle, row_function

        ir = functions.ir
        return {NAME: row_function(mapped_bundle(ir), readings.columns_function(ir), ca.MX)}, \
            {}, toolchain

    try:
        return compile_keyed(content, make, toolchain=toolchain)[NAME]
    except AnalysisError as error:
        warnings.warn(f"{str(error).splitlines()[0]}; the results row runs over the bundle's "
                      "functions", stacklevel=2)
        return None
