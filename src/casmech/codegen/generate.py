"""SystemFunctions -> C: a few translation units of balanced size (built in parallel), one
header. The functions come from codegen.mapped (kernels mapped over bodies, rows and force
elements), so the C holds each kernel once and grows with the model only by its index tables.

Each unit holds a function and, for the functions an integrator differentiates, its Jacobian
under the name casadi's External looks up (`jac_<name>`, inputs then nominal outputs), so an MX
graph over the loaded functions (casmech.optimal's constraints, or a C or casadi user's) is
differentiated through compiled code.
"""

from __future__ import annotations

from pathlib import Path

import casadi as ca

from casmech.codegen import manifest
from casmech.compiler import dae

# Functions whose Jacobian is generated as well (`jac_<name>`): the vector-valued ones an MX
# graph over the library differentiates (casmech.optimal; the augmented-Lagrangian fallback of
# runtime.dynamics did until it became Runge-Kutta steps, which only evaluate), and the DAE
# residuals (what IDAS integrates).
DIFFERENTIATED = frozenset({
    "phi", "nu", "gamma", "generalized_forces",
    "romega_forces", "romega_nu", "romega_gamma", "romega_q_dot",
})
# Matrix-valued functions that graph differentiates too get one forward and one reverse
# derivative instead (`fwd1_<name>`, `adj1_<name>`, which casadi's External uses the same way):
# their Jacobians are 3-D tensors whose sparsity tables in the C grow as N^2 (4 MB of C for the
# mass matrix of 128 bodies, gigabytes at 1000).
DIRECTIONAL = manifest.DIRECTIONAL  # {"mass_matrix", "phi_q", "romega_mass", "romega_jacobian"}
HEADER = "casmech_model.h"


def dae_functions(functions: dict[str, ca.Function]) -> dict[str, ca.Function]:
    """dae_<formulation> and dae_ggl_<formulation>: the DAE residuals IDAS integrates
    (compiler.dae, both stabilizations) over the given bundle, one per formulation (MX graphs
    of calls over the mapped bundle)."""
    return dae.residuals(functions)


def differentiated(functions: dict[str, ca.Function]) -> set[str]:
    """The functions generated with their Jacobian."""
    return {name for name in functions if name in DIFFERENTIATED or name.startswith("dae_")}


def derivatives(name: str, function: ca.Function, jacobians: set[str]) -> list[ca.Function]:
    if name in jacobians:
        return [function.jacobian()]
    return [function.forward(1), function.reverse(1)] if name in DIRECTIONAL else []


def units(functions: dict[str, ca.Function]) -> dict[str, list[ca.Function]]:
    """Function name -> the functions generated for it (itself, and its derivatives)."""
    jacobians = differentiated(functions)
    return {name: [f, *derivatives(name, f, jacobians)] for name, f in functions.items()}


def _cost(members: list[ca.Function]) -> int:
    return sum(f.n_instructions() for f in members)


def partition(groups: dict[str, list[ca.Function]], parts: int) -> list[list[ca.Function]]:
    """Split into at most `parts` translation units of about equal instruction count (largest
    first, each to the lightest unit), so parallel compilers finish together."""
    bins: list[list[ca.Function]] = [[] for _ in range(max(1, min(parts, len(groups))))]
    loads = [0] * len(bins)
    for members in sorted(groups.values(), key=_cost, reverse=True):
        lightest = loads.index(min(loads))
        bins[lightest] += members
        loads[lightest] += _cost(members)
    return [b for b in bins if b]


def write_sources(functions: dict[str, ca.Function], directory: Path,
                  parts: int = 1) -> list[Path]:
    """Write `casmech_model_<k>.c/.h` (k < parts) and HEADER including them; the C sources."""
    directory.mkdir(parents=True, exist_ok=True)
    sources = []
    for k, members in enumerate(partition(units(functions), parts)):
        generator = ca.CodeGenerator(f"casmech_model_{k}.c", {"with_header": True,
                                                              "verbose": False})
        for function in members:
            generator.add(function)
        generator.generate(str(directory) + "/")
        sources.append(directory / f"casmech_model_{k}.c")
    includes = "".join(f'#include "{path.stem}.h"\n' for path in sources)
    (directory / HEADER).write_text(
        "/* casmech generated model: every system function (casadi C API). Compile with\n"
        "   -std=c99 (gnu modes declare a math.h gamma() that clashes with ours). */\n"
        "#ifndef CASMECH_MODEL_H\n#define CASMECH_MODEL_H\n" + includes + "#endif\n")
    return sources
