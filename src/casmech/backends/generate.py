"""SystemFunctions -> C. The bundle (equations.functions.mapped_functions: kernels mapped over
bodies, rows and force elements) goes into a few translation units of balanced size (built in
parallel) behind one header; each DAE residual (formulations.residuals) into a unit and a
library of its own, since casadi's IDAS interface looks its residual and Jacobian up in the
DAE's library under the fixed names daeF and jacF. Neither grows with the model but for its
index tables.

Each bundle unit holds a function and, for the functions an MX graph over the library
differentiates (casmech.optimal's constraints, or a C or casadi user's), its Jacobian under the
name casadi's External looks up (`jac_<name>`, inputs then nominal outputs), or one forward and
one reverse derivative for the matrix-valued ones.
"""

from __future__ import annotations

from pathlib import Path

import casadi as ca

from casmech.backends import manifest
from casmech.backends.build import SUFFIX
from casmech.formulations import residuals

# Functions whose Jacobian is generated as well (`jac_<name>`): the vector-valued ones an MX
# graph over the library differentiates (casmech.optimal.compiled, r-p only). The romega_*
# functions are evaluated only (the runtime's fallback steps), so their derivatives, a large
# part of the bundle's gcc time, are not generated (docs/decisions/codegen-flags.md).
DIFFERENTIATED = frozenset({"phi", "nu", "gamma", "generalized_forces"})
# Matrix-valued functions that graph differentiates too get one forward and one reverse
# derivative instead (`fwd1_<name>`, `adj1_<name>`, which casadi's External uses the same way):
# their Jacobians are 3-D tensors whose sparsity tables in the C grow as N^2 (4 MB of C for the
# mass matrix of 128 bodies, gigabytes at 1000).
DIRECTIONAL = manifest.DIRECTIONAL  # {"mass_matrix", "phi_q"}
HEADER = "casmech_model.h"


def differentiated(functions: dict[str, ca.Function]) -> set[str]:
    """The functions generated with their Jacobian."""
    return {name for name in functions if name in DIFFERENTIATED}


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


def _unit(name: str, functions: list[ca.Function], directory: Path) -> Path:
    generator = ca.CodeGenerator(f"{name}.c", {"with_header": True, "verbose": False})
    for function in functions:
        generator.add(function)
    generator.generate(str(directory) + "/")
    return directory / f"{name}.c"


def write_units(groups: dict[str, list[ca.Function]], directory: Path, parts: int,
                prefix: str) -> list[Path]:
    """Write `<prefix>_<k>.c/.h` (k < parts) and `<prefix>.h` including them; the C sources.
    groups: name -> the functions generated for it (kept in one unit)."""
    return [source for sources in write_unit_sets([groups], directory, parts, prefix)
            for source in sources]


def write_unit_sets(sets: list[dict[str, list[ca.Function]]], directory: Path, parts: int,
                    prefix: str) -> list[list[Path]]:
    """write_units over several sets of groups (e.g. one per set of compiler flags), each set
    in up to `parts` units of its own, numbered on across the sets, behind one header; the C
    sources of each set."""
    directory.mkdir(parents=True, exist_ok=True)
    numbered, k = [], 0
    for set_units in (partition(groups, parts) for groups in sets):
        numbered.append([_unit(f"{prefix}_{k + j}", members, directory)
                         for j, members in enumerate(set_units)])
        k += len(set_units)
    sources = [source for set_sources in numbered for source in set_sources]
    includes = "".join(f'#include "{path.stem}.h"\n' for path in sources)
    guard = prefix.upper() + "_H"
    (directory / f"{prefix}.h").write_text(
        "/* casmech generated functions (casadi C API). Compile with -std=c99 (gnu modes\n"
        "   declare a math.h gamma() that clashes with ours). */\n"
        f"#ifndef {guard}\n#define {guard}\n" + includes + "#endif\n")
    return numbered


def write_sources(functions: dict[str, ca.Function], directory: Path,
                  parts: int = 1) -> list[Path]:
    """The bundle: `casmech_model_<k>.c/.h` (k < parts) and HEADER including them."""
    return write_units(units(functions), directory, parts, HEADER.removesuffix(".h"))


def dae_library(name: str) -> str:
    return f"libcasmech_{name}{SUFFIX}"


def write_dae_sources(oracles: dict[str, dict[str, ca.Function]], directory: Path
                      ) -> dict[str, list[Path]]:
    """Per DAE a unit `casmech_<dae name>.c/.h` (its function, daeF and jacF) and
    `casmech_<dae name>_patterns.c` (the Jacobian patterns casadi reads, see
    formulations.residuals.jacobian_patterns); library file name -> its sources."""
    directory.mkdir(parents=True, exist_ok=True)
    libraries = {}
    for name, functions in oracles.items():
        patterns = directory / f"casmech_{name}_patterns.c"
        patterns.write_text(patterns_source(residuals.jacobian_patterns(functions)))
        libraries[dae_library(name)] = [
            _unit(f"casmech_{name}", list(functions.values()), directory), patterns]
    return libraries


def patterns_source(patterns: dict[str, list[ca.Sparsity]]) -> str:
    """C defining jac_<name>_sparsity_out(i) for every function: the i-th block of its
    Jacobian (output-major) in casadi's compressed column format."""
    lines = ["/* Jacobian patterns (casmech.backends.generate.patterns_source): casadi's External",
             "   reads them from jac_<name>_sparsity_out. */",
             "#include <stddef.h>", "typedef long long int casadi_int;"]
    for name, blocks in patterns.items():
        for k, sparsity in enumerate(blocks):
            values = [sparsity.size1(), sparsity.size2(), *sparsity.colind(), *sparsity.row()]
            lines.append(f"static const casadi_int {name}_s{k}[{len(values)}] = "
                         f"{{{','.join(str(int(v)) for v in values)}}};")
        lines.append(f"const casadi_int* jac_{name}_sparsity_out(casadi_int i);")
        lines.append(f"const casadi_int* jac_{name}_sparsity_out(casadi_int i) {{")
        lines.append("  switch (i) {")
        lines += [f"    case {k}: return {name}_s{k};" for k in range(len(blocks))]
        lines += ["    default: return NULL;", "  }", "}"]
    return "\n".join(lines) + "\n"
