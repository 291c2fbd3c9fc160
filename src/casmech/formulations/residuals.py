"""The DAE residuals a library compiles, by the builder's switch (equations.evaluation):

- inline: the registered formulation's residual (formulations.protocol: for rp and romega
  formulations.dae's) over the interpreted bundle, one SX graph (its Jacobian by
  AD of the whole graph: from_residual), where that code is smaller and faster per call
  (WHERE_INLINE["dae_library"], UNROLLED_INSTRUCTIONS);
- mapped (`oracle`): the same residual (formulations.dae_terms) as a sum of elements
  (numerics.element_sums): one per joint, one per body, one per force element
  (formulations.residual_groups), whose kernels are formulations.residual_kernels, mapped over
  their instances, the Jacobian assembled from the kernels' own SX Jacobians: code that does not
  grow with the model (only index tables do; docs/decisions/codegen-element-residuals.md).

Each compiled residual is the DAE casadi's IDAS interface integrates together with `daeF` and
`jacF`, the residual and its Jacobian blocks, which that interface takes from the DAE's library
instead of building them (so each DAE gets a library of its own: backends.generate).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import casadi as ca

from casmech.equations.evaluation import Evaluation, is_inline
from casmech.equations.functions import build_functions
from casmech.formulations.registry import FORMULATIONS
from casmech.model.ir import ModelIR

if TYPE_CHECKING:  # (the element kernels are imported where a mapped residual is built)
    from casmech.formulations.residual_groups import Indices
    from casmech.numerics.element_sums import ElementSum

KINDS = {"ggl": "dae_ggl_", "projection": "dae_"}  # stabilization -> name prefix
# A library's DAE of a model the switch evaluates inline (WHERE_INLINE["dae_library"]) is
# compiled from its inline SX when its residual and Jacobian take at most UNROLLED_INSTRUCTIONS
# SX instructions together, else from the mapped element kernels: there the unrolled code runs
# faster per call and builds sooner; above, it gains little and builds slower
# (docs/decisions/codegen-small-dae-unrolled.md).
UNROLLED_INSTRUCTIONS = 12_000


def name(form: str, kind: str) -> str:
    return KINDS[kind] + form


def element_sum(ir: ModelIR, ix: Indices, t, constants: list, ev: Evaluation) -> ElementSum:
    """constants: the row constants of p, [w, s] (, s_phi for ggl) (formulations.dae)."""
    from casmech.formulations.residual_groups import body_group, force_groups, joint_groups
    from casmech.numerics.element_sums import ElementSum

    groups = [*joint_groups(ir, ix, t, constants, ev), *body_group(ir, ix, constants, ev),
              *force_groups(ir, ix, t, ev)]
    return ElementSum(ix.n_x + ix.n_z, ix.n_u, tuple(groups), ix.padding)


INTEGRATOR_IN = ["t", "x", "z", "p", "u"]  # casadi's DAE inputs (ca.dyn_in())


def oracles(ir: ModelIR) -> dict[str, dict[str, ca.Function]]:
    """Every DAE residual a library compiles (formulations.registry: each registered
    formulation's `residual` for its `library_stabilizations`; rp and romega, both
    stabilizations, built in) with its daeF and jacF: inline where the switch says so and
    the code is small (UNROLLED_INSTRUCTIONS), else mapped (oracle) where the formulation
    has element kernels (the body forms: formulations.residual_groups), else inline."""
    from casmech.formulations.table import BODY_FORMS

    sx = build_functions(ir) if is_inline("dae_library", ir.n_bodies) else None
    out = {}
    for formulation in FORMULATIONS.values():
        for kind in formulation.library_stabilizations():
            if formulation.name not in BODY_FORMS:  # no kernels: inline whatever its size
                inline = from_residual(formulation.residual(sx or build_functions(ir), kind))
                out[next(iter(inline))] = inline
                continue
            chosen = (from_residual(formulation.residual(sx, kind)) if sx is not None
                      else None)
            if chosen is not None and sum(chosen[f].n_instructions() for f in (
                    "daeF", "jacF")) > UNROLLED_INSTRUCTIONS:
                chosen = None
            out[name(formulation.name, kind)] = chosen or oracle(ir, formulation.name, kind)
    return out


def library_key() -> list:
    """What a library's cache key records of the residuals it compiles: each registered
    formulation that has some (its name, class and `library_stabilizations`), so registering
    one builds a library that holds it."""
    return [[f.name, f"{type(f).__module__}.{type(f).__qualname__}",
             list(f.library_stabilizations())]
            for f in FORMULATIONS.values() if f.library_stabilizations()]


def oracle(ir: ModelIR, form: str, kind: str, data: ca.SX | None = None
           ) -> dict[str, ca.Function]:
    """dae_[ggl_]<form> mapped, the DAE as IDAS integrates it, (t, x, z, p, u) -> (ode, alg,
    quad, zero), with `daeF` (its residual) and `jacF` (the Jacobian blocks d(ode, alg)/d(x,
    z)), the names casadi's IDAS interface looks up in the DAE's library. `data`: the symbols
    of a symbolic IR, whose values follow p's own."""
    from casmech.formulations.residual_groups import Indices
    from casmech.formulations.table import BODY_FORMS

    if form not in BODY_FORMS:
        raise ValueError(f"unknown formulation {form}")
    ix = Indices(ir, form, kind)
    n_data = 0 if data is None else data.numel()
    tau, x, z = ca.MX.sym("t"), ca.MX.sym("x", ix.n_x), ca.MX.sym("z", ix.n_z)
    p, u = ca.MX.sym("p", ix.n_p + n_data), ca.MX.sym("u", 0)
    ev = Evaluation(False, data, input=p[ix.n_p:]) if n_data else Evaluation.of(False)
    elements = element_sum(ir, ix, p[0] + tau, ix.constants(p), ev)
    unknowns = ca.vertcat(x, z)
    residual = elements.value(unknowns)
    ode, alg = residual[:ix.n_x], residual[ix.n_x:]
    xz = ((0, ix.n_x), (ix.n_x, ix.n_u))
    ode_x, ode_z, alg_x, alg_z = elements.jacobian(unknowns, xz, xz)
    ins = [tau, x, z, p, u]
    dae_name = name(form, kind)
    return {
        dae_name: ca.Function(dae_name, ins, [ode, alg, ca.MX(0, 1), ca.MX(0, 1)],
                              INTEGRATOR_IN, DYN_OUT),
        "daeF": ca.Function("daeF", ins, [ode, alg], INTEGRATOR_IN, ["ode", "alg"]),
        "jacF": ca.Function("jacF", ins, [ode_x, alg_x, ode_z, alg_z], INTEGRATOR_IN,
                            ["jac_ode_x", "jac_alg_x", "jac_ode_z", "jac_alg_z"]),
    }


DYN_OUT = ["ode", "alg", "quad", "zero"]  # casadi's DAE outputs (ca.dyn_out())


def jacobian_patterns(functions: dict[str, ca.Function]) -> dict[str, list[ca.Sparsity]]:
    """The Jacobian sparsity of the DAE function and of daeF, block by block (output-major:
    d output_i / d input_j), for jac_<name>_sparsity_out in the DAE's library: casadi's
    External reads a function's Jacobian pattern there and counts it dense without it, which
    makes IDAS's setup (Integrator::sp_jac_dae, from daeF) grow with the square of the model
    (docs/decisions/codegen-element-residuals.md). The (x, z) blocks are jacF's; the others
    come from CasADi's sparsity propagation through the function. The library holds no jac_<name>
    itself: AD through these functions stops with an error instead of using a pattern alone."""
    jac = functions["jacF"]
    known = {("ode", "x"): jac.sparsity_out(0), ("alg", "x"): jac.sparsity_out(1),
             ("ode", "z"): jac.sparsity_out(2), ("alg", "z"): jac.sparsity_out(3)}
    out = {}
    for function_name, function in functions.items():
        if function_name == "jacF":
            continue
        blocks = []
        for o in range(function.n_out()):
            for i in range(function.n_in()):
                block = (function.name_out(o), function.name_in(i))
                blocks.append(known[block] if block in known else function.jac_sparsity(o, i))
        out[function_name] = blocks
    return out


def from_residual(function: ca.Function) -> dict[str, ca.Function]:
    """The same three functions for any residual (t, x, z, p) -> (ode, alg) (SX or MX), its
    Jacobian blocks by CasADi's AD of the whole residual (e.g. the inline one)."""
    symbol = ca.SX if function.is_a("SXFunction") else ca.MX
    ins = [symbol.sym(n, function.sparsity_in(k)) for k, n in enumerate(function.name_in())]
    ins.append(symbol.sym("u", 0))
    ode, alg = function(*ins[:4])
    x, z = ins[1], ins[2]
    return {
        function.name(): ca.Function(function.name(), ins, [ode, alg, symbol(0, 1),
                                                            symbol(0, 1)],
                                     INTEGRATOR_IN, ["ode", "alg", "quad", "zero"]),
        "daeF": ca.Function("daeF", ins, [ode, alg], INTEGRATOR_IN, ["ode", "alg"]),
        "jacF": ca.Function("jacF", ins, [ca.jacobian(ode, x), ca.jacobian(alg, x),
                                          ca.jacobian(ode, z), ca.jacobian(alg, z)],
                            INTEGRATOR_IN, ["jac_ode_x", "jac_alg_x", "jac_ode_z", "jac_alg_z"]),
    }
