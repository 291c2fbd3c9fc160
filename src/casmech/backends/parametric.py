"""Compiled libraries that take the model data as an input: one build serves every value of the
model's parameters.

The bundle is the builder's (equations.functions) over model.parametric's symbolic IR (every
function with the trailing input `d`, the model data), evaluated inline: SX generated as C with
the derivatives codegen.generate adds (and, for kinematics and inverse dynamics,
formulations.prescribed's step over it, with `d` its third input); each DAE residual is
a registered formulation's (formulations.protocol: its `residual` for each of its
`library_stabilizations`; rp's and romega's are formulations.dae's) over that bundle,
(t, x, z, [p; d]), with its daeF and jacF (formulations.residuals.from_residual). The cache key is
the model's structure (model.parametric's signature) with its text, component files and
tables, never the values.
For a dynamics analysis the library also holds the joint formulation's functions (the
registered joint formulation's `equations` over the same symbolic IR, their trailing input the
model data with the tree's constants): the tree's ODE with its forward derivative or the
loops' DAE and its Jacobian by the states (joint_jacobian: never by d), the results rows, the
loops' start functions and joint_data, which computes that input from d.
Loading binds the values of this run: every function but the DAE residuals becomes an MX
wrapper calling its external with `d` given; the DAE residuals stay the externals (so IDAS takes
their daeF and jacF) and SystemFunctions.data carries `d`, which runtime.dynamics appends to the
integrator's p. The joint functions are bound to joint_data(d) and kept apart from the system
functions, in SystemFunctions.joint_functions (runtime.joint_dynamics takes them).
"""

from __future__ import annotations

import functools
import hashlib
import json
from pathlib import Path
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from casmech.backends import cache, external_record, manifest
from casmech.backends.build import LIBRARY, Toolchain
from casmech.backends.load import externals, metadata
from casmech.core.version import VERSION
from casmech.equations.evaluation import WHERE_INLINE
from casmech.equations.functions import Library, SystemFunctions, build_functions
from casmech.formulations import residuals
from casmech.formulations.registry import FORMULATIONS
from casmech.formulations.tree import spanning_tree
from casmech.model.ir import ModelIR
from casmech.numerics import lazy_jacobian
from casmech.schema.resolved import ResolvedModel

if TYPE_CHECKING:  # (model.parametric is imported where a parametric library is built)
    from casmech.model import parametric

MAX_BODIES = WHERE_INLINE["parametric"]  # above: the mapped library, the values in its key
PRESCRIBED_ANALYSES = ("kinematics", "inverse_dynamics")  # as codegen's: prescribed_step too
JOINT_ANALYSES = ("dynamics",)  # the joint formulation's functions too
JOINT_DATA = "joint_data"
JOINT_JACOBIAN = "joint_jacobian"  # the ODE's or DAE's Jacobian by the states, not by d


def applies(model: ResolvedModel) -> bool:
    """Whether `compiled` builds the parametric library: a model with parameters, up to
    MAX_BODIES bodies (its functions are inline: C that grows with the model; the mapped
    library's does not)."""
    return bool(model.parameters) and len(model.bodies) <= MAX_BODIES


def key(model: ResolvedModel, signature: str, toolchain: Toolchain, dae: bool) -> str:
    """The cache key: the model's content without its parameter values, its structure, the
    versions, the toolchain and (`dae`) the residuals the registered formulations compile."""
    content = json.dumps({"format": manifest.FORMAT, "kind": "parametric",
                          "model": cache.model_digest(model, values=False),
                          "structure": signature, "casmech": VERSION,
                          "sources": cache.source_digest(), "casadi": ca.__version__,
                          "compiler": toolchain.version(), "flags": list(toolchain.all_flags),
                          "dae": residuals.library_key() if dae else False})
    return hashlib.sha256(content.encode()).hexdigest()[:32]


def joint_functions(split: parametric.Split) -> dict[str, list[ca.Function]]:
    """The joint formulation's functions by name, each with what is generated with it (as
    runtime.joint_dynamics.compiled_system for a numeric bundle: a tree's ODE with its forward
    derivative, whose Jacobian a symbolic AD would make huge on a long chain; the loops' DAE
    with its Jacobian by the states as a function of its own); none for loops through a
    floating body."""
    if spanning_tree(split.ir).floating_loops:  # auto runs rp (runtime.auto_formulation)
        return {}
    system = FORMULATIONS["joint"].equations(split.ir, split.symbols)
    dynamics = {system.dynamics.name(): [system.dynamics]}
    if system.n_cut:  # the DAE's Jacobian by the states, never by d
        dynamics[JOINT_JACOBIAN] = [lazy_jacobian.data_jacobian(system.dynamics, JOINT_JACOBIAN)]
    else:  # a tree's: by forward sweeps (JointSystem.problem), the derivative casadi looks up
        dynamics["joint_ode"].append(system.dynamics.forward(1))
    return {**dynamics, "joint_motion": [system.motion],
            "joint_acceleration_system": [system.acceleration_system],
            "joint_velocity_jacobian": [system.velocity_jacobian],
            "joint_relative_states": [system.relative_states], JOINT_DATA: [system.data]}


def bundle(ir: ModelIR, dae: bool) -> tuple[dict[str, ca.Function], dict[str, ca.Function]]:
    """(the system functions with input d, the DAE residuals over them by name)."""
    from casmech.formulations import prescribed
    from casmech.model import parametric

    split = parametric.split(ir)
    built = build_functions(split.ir, split.symbols)
    functions = built.functions
    if ir.analysis.type in PRESCRIBED_ANALYSES:  # as codegen.bundle, d its third input
        functions["prescribed_step"] = prescribed.step(functions)
    oracles = {}
    if dae:  # each registered formulation's residuals (formulations.protocol)
        for formulation in FORMULATIONS.values():
            for kind in formulation.library_stabilizations():
                residual = formulation.residual(built, kind)
                oracles[residual.name()] = residuals.from_residual(residual)
    return functions, oracles


def write_build(ir: ModelIR, directory: Path, toolchain: Toolchain, info: dict, dae: bool,
                build_libraries) -> Path:
    from casmech.backends import generate  # (on a build only: a warm run writes no C)
    from casmech.model import parametric

    functions, oracles = bundle(ir, dae)
    joint = (joint_functions(parametric.split(ir)) if ir.analysis.type in JOINT_ANALYSES
             else {})
    groups = generate.units(functions) | joint
    sources = generate.write_units(groups, directory, toolchain.jobs,
                                   generate.HEADER.removesuffix(".h"))
    dae_sources = generate.write_dae_sources(oracles, directory)
    build_libraries({LIBRARY: sources, **dae_sources}, directory, toolchain)
    listed = {**functions, **{n: members[0] for n, members in joint.items()},
              **{n: o[n] for n, o in oracles.items()}}
    return manifest.write(directory, listed, generate.differentiated(functions), {
                              **info, "parametric": True, "parameters": list(ir.parameters),
                              "data": int(functions["phi"].size1_in(2)),
                              "casmech": VERSION,
                              "casadi": ca.__version__, "compiler": toolchain.compiler,
                              "compiler_version": toolchain.version(),
                              "flags": list(toolchain.all_flags), "library": LIBRARY,
                              "header": generate.HEADER},
                          {n: generate.dae_library(n) for n in oracles})


def bind(function: ca.Function, values: np.ndarray, name: str | None = None,
         first: bool = False) -> ca.Function:
    """The function without its trailing input d, called with d = values (under `name`; only
    its first output if `first`), recorded as such (backends.external_record)."""
    inputs = [ca.MX.sym(function.name_in(k), function.sparsity_in(k))
              for k in range(function.n_in() - 1)]
    outputs = function.call([*inputs, ca.DM(values)])
    names = function.name_out()
    if first:
        outputs, names = outputs[:1], names[:1]
    return external_record.bound(
        ca.Function(name or function.name(), inputs, outputs, function.name_in()[:-1], names),
        function, values)


@functools.lru_cache(maxsize=8)
def _externals(directory: str, built: int) -> dict[str, ca.Function]:
    """The library's externals, loaded once per process and build (`built`: its manifest's
    mtime): a sweep binds them to every sample's values
    (docs/decisions/joint-system-over-model-data.md)."""
    return externals(Path(directory))


def library_functions(directory: Path) -> dict[str, ca.Function]:
    """The library's functions as built, each with the model data d its last input (the
    process's copy: callers must not change the dict)."""
    built = (directory / manifest.MANIFEST).stat().st_mtime_ns
    return _externals(str(directory.resolve()), built)


def load(directory: Path, ir: ModelIR, values: np.ndarray,
         signature: str | None = None) -> SystemFunctions:
    """The library's functions bound to the model data `values` (of `ir`, whose structure's
    `signature` the library was built for)."""
    loaded = dict(library_functions(directory))
    joint = {name: loaded.pop(name) for name in list(loaded) if name.startswith("joint_")}
    functions = {name: f if name.startswith("dae_") else bind(f, values)
                 for name, f in loaded.items()}
    bound = None
    if joint:
        joint_data = np.array(joint.pop(JOINT_DATA)(values).full()).ravel()
        dynamics = "joint_dae" if "joint_dae" in joint else "joint_ode"
        bound = {  # the Jacobian under casadi's name for it
            name: bind(f, joint_data, f"jac_{dynamics}" if name == JOINT_JACOBIAN else None)
            for name, f in joint.items()}
    return SystemFunctions(functions, **metadata(ir), data=values, mode="compiled",
                           joint_functions=bound, parametric=Library(directory, signature))
