"""manifest.json: what a generated library holds and how it was built."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import casadi as ca

MANIFEST = "manifest.json"
# generated with fwd1_<name> and adj1_<name> (codegen.generate); kept here to avoid a cycle
DIRECTIONAL = frozenset({"mass_matrix", "phi_q"})
# bump when the layout of a build directory changes (2: a library per DAE; 3: the libraries'
# sha256, codegen.trust)
FORMAT = 3
DIGESTS = "library_sha256"  # key: library file name -> sha256 of its bytes at build
KEPT = ".casadi"  # a kept function's file (library.compile_keyed): CasADi's serialization


def _sparsity(sparsity: ca.Sparsity) -> dict:
    return {"rows": sparsity.size1(), "columns": sparsity.size2(), "nnz": sparsity.nnz(),
            "colind": [int(k) for k in sparsity.colind()],
            "row": [int(k) for k in sparsity.row()]}


def describe(function: ca.Function) -> dict:
    """Name, inputs and outputs (name, size, sparsity in compressed-column form)."""
    return {
        "name": function.name(),
        "inputs": [{"name": function.name_in(k), **_sparsity(function.sparsity_in(k))}
                   for k in range(function.n_in())],
        "outputs": [{"name": function.name_out(k), **_sparsity(function.sparsity_out(k))}
                    for k in range(function.n_out())],
    }


def sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def write(directory: Path, functions: dict[str, ca.Function], differentiated, info: dict,
          libraries: dict[str, str] | None = None) -> Path:
    """Every function with its library file (`libraries`: name -> file; default: the
    bundle's, info["library"]) and whether its derivatives are generated too, and the sha256
    of every library (DIGESTS: what codegen.trust checks before a load)."""
    libraries = libraries or {}
    entries = [{**describe(f), "library": libraries.get(name, info.get("library")),
                "jacobian": name in differentiated, "forward_reverse": name in DIRECTIONAL}
               for name, f in functions.items()]
    files = sorted({entry["library"] for entry in entries if entry["library"]})
    digests = {name: sha256(directory / name) for name in files}
    path = directory / MANIFEST
    path.write_text(json.dumps({"format": FORMAT, **info, "functions": entries,
                                DIGESTS: digests}, indent=1))
    return path


def read(directory: Path) -> dict:
    return json.loads((directory / MANIFEST).read_text())


def sparsity(entry: dict) -> ca.Sparsity:
    """The casadi.Sparsity of an input or output entry."""
    return ca.Sparsity(entry["rows"], entry["columns"], entry["colind"], entry["row"])
