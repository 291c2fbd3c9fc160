"""What goes into the C of a compiled bundle's joint system (runtime.joint_dynamics): which
functions, under which names, at which flags.

  - the results rows' function above WHOLE_INSTRUCTIONS is compiled as a chain of parts of at
    most PART_INSTRUCTIONS instructions each (backends.split; motion_parts names them), which gcc
    compiles in units at once; once loaded, `joined` makes joint_motion of them again and
    backends.rows_loop evaluates it part by part over the rows (rows_loop.chained);
  - the SELDOM functions are compiled at QUICK_FLAGS, the results rows (joint_motion or its
    parts) at ROWS_FLAGS, and an ODE above the settings' quick_build_instructions at
    QUICK_FLAGS whole, unless the user chose flags ($CASMECH_CFLAGS);
  - BDF's Jacobian (forward sweeps of the ODE: numerics.lazy_jacobian) comes from a library of
    its own, the ODE and its forward derivative at the library's flags, built when a BDF run
    first asks for it (keyed_jacobian, content_jacobian: JointSystem.identity_jacobian's
    place), so that a run on Adams, the rule for these trees, never compiles it at -O1.
Both choices are functions of the functions, the settings, chosen_flags() and machine(),
so a library keyed by those (backends.library.compile_keyed) stays
honest.
"""

from __future__ import annotations

import os
from collections.abc import Callable

import casadi as ca

from casmech.backends.build import (
    DEFAULT_FLAGS,
    FLAGS_ENVIRONMENT,
    Toolchain,
    default_compiler,
    machine_flags,
    takes_machine_flags,
)
from casmech.backends.library import compile_functions, compile_keyed
from casmech.backends.rows_loop import chained
from casmech.formulations.joint_system import JointSystem, layout
from casmech.formulations.tree import Tree
from casmech.numerics import lazy_jacobian

# the results rows above WHOLE_INSTRUCTIONS SX instructions are compiled as a chain of parts of
# at most PART_INSTRUCTIONS each: evaluated part by part over a block's rows, a part's machine
# code stays in the instruction cache, where the whole function's is fetched again on every
# row; below it the whole function's code stays there, and a chain would only add the writes
# and reads of its shared values (docs/decisions/results-rows-cost.md)
WHOLE_INSTRUCTIONS = 6_000
PART_INSTRUCTIONS = 3_500
MOTION_PART = "joint_motion_part"  # the parts' names: joint_motion_part0, joint_motion_part1, ...
QUICK_FLAGS = ("-O0",)
# evaluated once per run, by method auto's stiffness probe (BDF's Newton iteration takes its
# Jacobian from keyed_jacobian's library); -O1 would more than treble their gcc time
SELDOM = ("fwd1_joint_ode",)
# the results rows' units, run once per output row: -Os code is shorter and these
# straight-line functions are fetched again on every row, which runs them faster than at -O1;
# the tree's ODE stays at the library's flags, its -Os code's speed depends on where the
# library's pages lie (docs/decisions/second-call-c.md)
ROWS_FLAGS = ("-Os",)


def motion_parts(count: int) -> tuple[str, ...]:
    """The library names of a chain of `count` parts of the results rows."""
    return tuple(f"{MOTION_PART}{k}" for k in range(count))


def motion(function: ca.Function) -> dict[str, ca.Function]:
    """The results rows' function by library name: joint_motion, or above WHOLE_INSTRUCTIONS
    its chain of parts (one per PART_INSTRUCTIONS instructions, rounded up)."""
    from casmech.backends.split import parts  # (on a build only)

    instructions = function.n_instructions()
    count = -(-instructions // PART_INSTRUCTIONS) if instructions > WHOLE_INSTRUCTIONS else 1
    chain = parts(function, motion_parts(count)) if count > 1 else None
    return dict(zip(motion_parts(count), chain, strict=True)) if chain else {
        "joint_motion": function}


def joined_library(library: dict[str, ca.Function]) -> dict[str, ca.Function]:
    """A loaded library with its results rows' parts joined into joint_motion, evaluated over
    rows part by part (rows_loop.chained)."""
    count = sum(1 for name in library if name.startswith(MOTION_PART))
    if not count:
        return library
    from casmech.backends.split import joined  # (only a library with the rows in parts)

    chain = [library[name] for name in motion_parts(count)]
    return {**library, "joint_motion": chained(joined(chain, "joint_motion"), chain)}


def chosen_flags() -> str | None:
    """The flags the user chose ($CASMECH_CFLAGS), or None: what `toolchain` depends on besides
    its arguments, so part of the library's key."""
    return os.environ.get(FLAGS_ENVIRONMENT)


def is_rows(name: str) -> bool:
    """Whether library function `name` is the results rows' (joint_motion or one of its
    parts)."""
    return name == "joint_motion" or name.startswith(MOTION_PART)


def machine() -> tuple[str, ...]:
    """The machine's instruction set the library's loop functions are built with
    (build.machine_flags) where the default compiler takes it (build.takes_machine_flags),
    else none: what toolchain adds and the library's key records."""
    return machine_flags() if takes_machine_flags(default_compiler()) else ()


def toolchain(instructions: int, quick_build_instructions: int, names=()) -> Toolchain:
    """The default toolchain where the user chose flags ($CASMECH_CFLAGS); else at QUICK_FLAGS
    for an ODE of more than quick_build_instructions SX `instructions`, and below that the
    library at DEFAULT_FLAGS, the SELDOM functions at QUICK_FLAGS and the results rows among
    the library's function `names` at ROWS_FLAGS, each but SELDOM with machine()'s
    instruction set."""
    if chosen_flags() is not None:
        return Toolchain()
    if instructions > quick_build_instructions:
        return Toolchain(flags=QUICK_FLAGS)
    extra = machine()
    return Toolchain(flags=DEFAULT_FLAGS + extra,
                     function_flags=tuple((name, QUICK_FLAGS) for name in SELDOM)
                     + tuple((name, ROWS_FLAGS + extra) for name in sorted(names)
                             if is_rows(name)))


def _bdf(ode: ca.Function, quick_build_instructions: int
         ) -> tuple[dict[str, ca.Function], Toolchain]:
    """The BDF Jacobian's library: the ODE and its forward derivative, and its toolchain (the
    library's flags, none of its own)."""
    chain = toolchain(ode.n_instructions(), quick_build_instructions)
    return ({"joint_ode": ode, "fwd1_joint_ode": ode.forward(1)},
            Toolchain(chain.compiler, chain.flags, chain.jobs))


def keyed_jacobian(content: dict, ode: Callable[[], ca.Function],
                   quick_build_instructions: int) -> Callable[[], ca.Function]:
    """() -> the ODE's Jacobian (jacobian()'s signature) by forward sweeps of a library cached
    under the joint library's `content` and this part, ode() giving the SX ODE on a miss."""
    def jacobian() -> ca.Function:
        def make():
            functions, chain = _bdf(ode(), quick_build_instructions)
            return functions, {}, chain

        library = compile_keyed({**content, "part": "BDF Jacobian"}, make)
        return lazy_jacobian.jacobian(library["joint_ode"])

    return jacobian


def content_jacobian(ode: ca.Function, quick_build_instructions: int
                     ) -> Callable[[], ca.Function]:
    """keyed_jacobian's Jacobian from a library keyed by the ODE's content."""
    def jacobian() -> ca.Function:
        functions, chain = _bdf(ode, quick_build_instructions)
        return lazy_jacobian.jacobian(compile_functions(functions, toolchain=chain)["joint_ode"])

    return jacobian


def system_from(tree: Tree, library) -> JointSystem:
    """A joint system of library functions under their library names (joint_ode or
    joint_dae, joint_motion, joint_acceleration_system, joint_velocity_jacobian,
    joint_relative_states; joint_jacobian, joint_solved_motion where there)."""
    dynamics = library["joint_dae" if tree.cut else "joint_ode"]
    return JointSystem(tree, layout(tree), tuple(r for j in tree.cut for r in j.rows),
                       dynamics, library["joint_motion"], library["joint_acceleration_system"],
                       library["joint_velocity_jacobian"], library["joint_relative_states"],
                       given_jacobian=library.get("joint_jacobian"),
                       solved_motion=library.get("joint_solved_motion"))
