"""A compiled SystemFunctions: casadi.external over the generated libraries, interchangeable
with the interpreted bundle (same names, inputs, outputs and sparsity), plus the DAE residuals
dae_[ggl_]<formulation> in the form IDAS integrates (formulations.residuals)."""

from __future__ import annotations

from pathlib import Path

import casadi as ca

from casmech.backends import external_record, trust
from casmech.backends.build import LIBRARY
from casmech.backends.manifest import KEPT
from casmech.equations.functions import JointMeta, SystemFunctions
from casmech.model.ir import GROUND_INDEX, ModelIR


def metadata(ir: ModelIR) -> dict:
    """The SystemFunctions fields other than `functions` (as equations.functions builds them),
    without building a symbolic graph."""
    names = tuple(b.name for b in ir.bodies)

    def body_name(k: int) -> str:
        return "ground" if k == GROUND_INDEX else names[k]

    joints = tuple(JointMeta(j.name, j.type, j.rows, body_name(j.body_i), body_name(j.body_j),
                             j.source) for j in ir.joints)
    return {"body_names": names, "joints": joints, "rows": tuple(ir.row_info()), "ir": ir}


def externals(directory: Path) -> dict[str, ca.Function]:
    """Every function the manifest of a build directory lists, loaded from its library once
    codegen.trust has found the directory the user's and its libraries as built (a
    UsageError naming what is wrong otherwise; nothing is loaded then)."""
    entries = trust.verify(directory, LIBRARY)["functions"]
    return {entry["name"]: _loaded(entry["name"], directory / (entry.get("library") or LIBRARY))
            for entry in entries}


def _loaded(name: str, path: Path) -> ca.Function:
    """A function from its library (recorded with its file: backends.external_record), or from
    CasADi's serialization of it (a kept function of backends.library.compile_keyed)."""
    if path.name.endswith(KEPT):
        return ca.Function.load(str(path))
    path = path.resolve()
    return external_record.loaded(ca.external(name, str(path)), path)


def load(directory: Path, ir: ModelIR) -> SystemFunctions:
    """The bundle of a build directory over `ir` (the IR it was built from), carrying the
    directory's cache key."""
    return SystemFunctions(externals(directory), **metadata(ir), mode="compiled",
                           library_key=directory.name)


def mode_of(functions: SystemFunctions) -> str:
    """'compiled' when the bundle's functions are loaded from a library, else 'interpreted':
    the bundle's own `mode` when its builder set it, else told from its functions."""
    if functions.mode is not None:
        return functions.mode
    kinds = {f.class_name() for f in functions.functions.values()}
    bound = functions.data is not None  # externals with the model data bound (parametric)
    return "compiled" if kinds == {"External"} or bound else "interpreted"
