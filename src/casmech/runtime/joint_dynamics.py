"""Forward dynamics in joint coordinates (analysis.formulation: joint) over the output grid:
a tree's ODE by DOP853 (runtime.dop853) or CVODES via CasADi, the stabilized index-2 DAE of a
tree with loop closures by IDAS (formulations/joint_system.py).

The initial state is the r-p one (assembly: the file's pose assembled, its velocities projected
onto the constraints), mapped to joint coordinates joint by joint (relative pose -> theta,
relative twist -> u through the joint's motion subspace), so every formulation starts from the
same state. Loop closures start from their consistent multipliers (the acceleration-level
constraints solved for lam; the ABA's accelerations are affine in lam), with the rows that
depend on the others at t0 masked out; the reactions are then reported as the minimum-norm
ones, as the r-p DAE does. Each results row holds the r-p state the tree gives and every joint
row's multiplier, the loops' from IDAS's algebraic states, or with `loop_rows: solved` solved
at the row's state (runtime.joint_rows). The grid is integrated in chunks of `joint_chunk`
output intervals (core.options.DynamicsSolver) by runtime.driver, a chunk a solver fails on
again in halves.
The spanning tree, the joint system, the starts and the integrators are kept in the run's
workspace (runtime.workspace).
"""

from __future__ import annotations

import sys
from dataclasses import asdict, replace

import casadi as ca
import numpy as np

from casmech.core.options import Assembly, DynamicsOptions, DynamicsSolver, JointCompile
from casmech.equations.functions import SystemFunctions
from casmech.errors import Interrupted
from casmech.formulations.joint_start import Loops, initial_state, quaternion_signs
from casmech.formulations.joint_system import JointSystem, build, saddle_terms
from casmech.formulations.tree import Tree, spanning_tree
from casmech.runtime import assembly, contact_steps, dop853, events, nonfinite
from casmech.runtime.buffers import NamedCall
from casmech.runtime.joint_recorder import Recorder
from casmech.runtime.joint_run import JointRun
from casmech.runtime.kinematics import output_times
from casmech.runtime.projected_loops import dop853_of, loop_algebraic, loop_ode_of
from casmech.runtime.results import Result
from casmech.runtime.workspace import Workspace, of

DEFAULT, METHOD = DynamicsSolver(), DynamicsOptions().method  # core.options
METHODS = {"adams": {"linear_multistep_method": "adams",
                     "nonlinear_solver_iteration": "functional"},
           "bdf": {"linear_multistep_method": "bdf", "nonlinear_solver_iteration": "newton"}}
# method auto: BDF when the ODE's fastest eigenvalue at t0 times the output step exceeds
# stiff_threshold (the measurements behind it: docs/decisions/method-auto.md).

# On a compiled bundle the tree's functions are unrolled SX compiled to C, whose build grows
# with the tree: the ODE up to compile.ode_bodies, the results rows (called once per output
# block) up to compile.motion_bodies; larger trees stay interpreted. An ODE above
# compile.quick_build_instructions SX instructions is built at -O0 unless $CASMECH_CFLAGS says
# otherwise (gcc -O1 time grows faster than the function; docs/decisions/joint-tree-compiled.md).


def tree_of(functions: SystemFunctions, workspace: Workspace | None = None) -> Tree:
    """The bundle's spanning tree (formulations.tree), found once per workspace."""
    return of(functions, workspace).one("spanning_tree", lambda: spanning_tree(functions.ir))


def _compiled(functions: SystemFunctions) -> bool:
    """Whether the bundle is compiled (codegen.mode_of), importing no code generation when
    none was: a compiled bundle is loaded only through casmech.backends."""
    codegen = sys.modules.get("casmech.backends.codegen")
    return codegen is not None and codegen.mode_of(functions) == "compiled"


def lags_bundle(functions: SystemFunctions, settings: JointCompile = DEFAULT.compile) -> bool:
    """Whether the bundle is compiled and its joint system would not be: a parametric bundle
    (functions.data) whose library holds no joint functions (built for another analysis; it
    would compile per value) or a bundle above settings.ode_bodies."""
    return _compiled(functions) and (
        functions.n_bodies > settings.ode_bodies or (
            functions.data is not None and functions.joint_functions is None))


def joint_system(functions: SystemFunctions, settings: DynamicsSolver = DEFAULT,
                 workspace: Workspace | None = None) -> JointSystem:
    """The bundle's joint system, built once per workspace and compile settings: from a
    parametric library's joint functions (library_system), else over the bundle's IR, and
    with a compiled bundle the tree's ODE or the loops' DAE and the results rows compiled too
    (compiled_system, lags_bundle)."""
    workspace = of(functions, workspace)
    compile_ = settings.compile

    def make() -> JointSystem:
        if functions.joint_functions is not None:
            return library_system(functions, workspace)
        if _compiled(functions) and not lags_bundle(functions, compile_):
            if functions.library_key is not None:
                return keyed_system(functions, settings, workspace)
            system = _built(functions, settings, workspace)
            with_motion, rows = _compiled_parts(functions, system, settings)
            return compiled_system(system, with_motion, settings, rows)
        return _built(functions, settings, workspace, mapped=True)

    return workspace.kept("joint_system", (compile_, settings.stiff_states, settings.loop_rows),
                          make)


def _built(functions: SystemFunctions, settings: DynamicsSolver,
           workspace: Workspace, mapped: bool = False) -> JointSystem:
    """The joint system's symbolic build over the bundle's IR; `mapped`: a tree above
    compile.mapped_bodies that formulations.mapped_system covers as its kernels' graph."""
    from casmech.formulations import mapped_system

    tree = tree_of(functions, workspace)
    if mapped and mapped_system.chosen(functions.ir, tree, settings.compile.mapped_bodies):
        from casmech.backends import tree_kernels

        kernels = tree_kernels.for_tree(functions.ir, tree)
        if kernels:  # else (no compiler, no usable cache) the unrolled SX runs faster
            return mapped_system.build(functions.ir, tree, kernels)
    return build(functions.ir, tree, identity_states=settings.stiff_states)


def _compiled_parts(functions: SystemFunctions, system: JointSystem,
                    settings: DynamicsSolver) -> tuple[bool, ca.Function | None]:
    """compiled_system's (with_motion, rows) for a compiled bundle's built `system`: the results
    rows compiled up to compile.motion_bodies, and with them for loop_rows solved the loops'
    rows solved at each state (runtime.joint_rows.solved_motion)."""
    from casmech.runtime.joint_rows import solved_motion

    with_motion = functions.n_bodies <= settings.compile.motion_bodies
    solved = with_motion and bool(system.n_cut) and settings.loop_rows == "solved"
    if not solved:
        return with_motion, None
    return with_motion, solved_motion(saddle_terms(functions.ir, system.tree), system.motion)


def library_system(functions: SystemFunctions,
                   workspace: Workspace | None = None) -> JointSystem:
    """The joint system of a parametric library's functions, bound to this bundle's values
    (codegen.parametric), over the numeric IR's tree."""
    from casmech.backends.joint_library import system_from

    return system_from(tree_of(functions, workspace), functions.joint_functions)


def keyed_system(functions: SystemFunctions, settings: DynamicsSolver = DEFAULT,
                 workspace: Workspace | None = None) -> JointSystem:
    """A compiled bundle's joint system from a library cached under the bundle's own library
    key and the settings that shape it (backends.library.compile_keyed), so that a warm cache
    builds no symbolic graph: on a miss, the system is built and what compiled_system compiles
    is compiled, and the functions a run evaluates a few times (the start's and the loops'
    acceleration_system, velocity_jacobian, relative_states, and the results rows above
    compile.motion_bodies) are kept as CasADi's serialization beside it: relative_states as
    one mapped call over the tree joints (formulations.mapped_rows), a fraction of the
    unrolled graph's size and load time."""
    from casmech.backends import joint_library
    from casmech.backends.library import compile_keyed

    workspace = of(functions, workspace)
    tree = tree_of(functions, workspace)
    name = "joint_dae" if tree.cut else "joint_ode"
    content = {"kind": "joint system", "bundle": functions.library_key,
               "compile": asdict(settings.compile), "stiff_states": settings.stiff_states,
               "loop_rows": settings.loop_rows, "chosen_flags": joint_library.chosen_flags(),
               "machine_flags": list(joint_library.machine())}

    def make():
        from casmech.formulations.mapped_rows import relative_states

        system = _built(functions, settings, workspace)
        with_motion, rows = _compiled_parts(functions, system, settings)
        compiled = _library_functions(system, with_motion, settings, rows)
        kept = {"joint_acceleration_system": system.acceleration_system,
                "joint_velocity_jacobian": system.velocity_jacobian,
                "joint_relative_states": relative_states(tree, functions.n_bodies)}
        if not with_motion:
            kept["joint_motion"] = system.motion
        return compiled, kept, _toolchain(system, settings.compile.quick_build_instructions,
                                          compiled)

    library = compile_keyed(content, make, with_jacobian=[name] if tree.cut else ())
    system = joint_library.system_from(tree, joint_library.joined_library(library))
    if "fwd1_joint_ode" not in library:
        return system
    return replace(system, identity_jacobian=joint_library.keyed_jacobian(
        content, lambda: _built(functions, settings, workspace).dynamics,
        settings.compile.quick_build_instructions))


def _library_functions(system: JointSystem, with_motion: bool, settings: DynamicsSolver,
                       rows: ca.Function | None) -> dict[str, ca.Function]:
    """What a compiled bundle's joint system compiles, by library name: the tree's ODE (with
    its forward derivative where method auto may choose BDF, up to settings.stiff_states) or
    the loops' DAE, with_motion the results rows (backends.joint_library.motion: large ones as
    two halves, joined again once loaded), and `rows`, the loops' rows solved at each state
    (runtime.joint_rows.solved_motion)."""
    from casmech.backends.joint_library import motion

    name = "joint_dae" if system.n_cut else "joint_ode"
    functions = {name: system.dynamics}
    if with_motion:
        functions |= motion(system.motion)
    if rows is not None:
        functions["joint_solved_motion"] = rows
    if not system.n_cut and system.layout.n_x <= settings.stiff_states:
        functions["fwd1_joint_ode"] = system.dynamics.forward(1)
    return functions


def compiled_system(system: JointSystem, with_motion: bool = True,
                    settings: DynamicsSolver = DEFAULT,
                    rows: ca.Function | None = None) -> JointSystem:
    """A tree's ODE or the loops' DAE (and with_motion the results rows) compiled through
    codegen's cache, keyed by their content (_library_functions); with the tree's ODE its
    forward derivative (casadi's externals find fwd1_<name> in their library: method auto's
    probe by forward sweeps of the compiled ODE; BDF's Jacobian from a library of its own,
    built on first use: backends.joint_library; the interpreted RNEA identity is dropped: the
    identity's C would lengthen the cold build, joint-derivatives.md), with the DAE its
    Jacobian (JointSystem.problem); `rows`, the loops' rows solved at each state
    (runtime.joint_rows.solved_motion), in the same library."""
    from casmech.backends import codegen
    from casmech.backends.joint_library import content_jacobian, joined_library

    name = "joint_dae" if system.n_cut else "joint_ode"
    functions = _library_functions(system, with_motion, settings, rows)
    quick = settings.compile.quick_build_instructions
    built = joined_library(codegen.compile_functions(
        functions, toolchain=_toolchain(system, quick, functions),
        with_jacobian=[name] if system.n_cut else ()))
    jacobian = content_jacobian(system.dynamics, quick) if "fwd1_joint_ode" in functions \
        else None
    return replace(system, dynamics=built[name],
                   motion=built.get("joint_motion", system.motion), identity_jacobian=jacobian,
                   solved_motion=built.get("joint_solved_motion"))


def _toolchain(system: JointSystem, quick_build_instructions: int, names=()):
    """The toolchain of the system's library of functions `names`
    (backends.joint_library.toolchain)."""
    from casmech.backends.joint_library import toolchain

    return toolchain(system.dynamics.n_instructions(), quick_build_instructions, names)


class _Integrator:
    """One SUNDIALS call over a chunk of the output grid: CVODES for a tree, IDAS for loops."""

    def __init__(self, system: JointSystem, loops: Loops, rtol: float, atol: float,
                 method: str, workspace: Workspace, settings: DynamicsSolver = DEFAULT):
        self.system, self.loops, self.workspace = system, loops, workspace
        self.settings = settings
        self.options = {"reltol": rtol, "abstol": atol, "disable_internal_warnings": True,
                        **nonfinite.SOLVER_OPTIONS}
        if not system.n_cut and method in METHODS:
            self.options |= METHODS[method]
        self.method, self.steps, self._options_key = method, 0, None
        self.loop, self.solved = None, True  # dop853 with loops: set by run_joint_dynamics
        self.derived: dict | None = None  # the start's derived entries (_kept_start)
        self._rk = None  # dop853: the integrator its first call found (loop, key: final then)

    def __call__(self, t0: float, times, x, z, trial: bool = False
                 ) -> tuple[np.ndarray, np.ndarray]:
        """States and algebraic states at `times` from (t0, x, z). trial: times are an event's
        trial point (runtime.events) and the end of its interval; CVODES integrates to the
        trial point only (its instance not kept for later runs), IDAS to the end with its
        first step sized by the whole interval (an index-2 DAE fails on a very short one)."""
        system = self.system
        if not len(x):  # every coordinate driven: nothing to integrate
            return np.zeros((0, len(times))), np.zeros((0, len(times)))
        if self.method == "dop853":  # runtime.dop853, kept (docs/decisions/dop853.md); loops:
            rk = self._rk
            if rk is None:  # with loops: their projected ODE (runtime.projected_loops)
                rk = self._rk = dop853_of(system, self.loop, self.options, self._key(),
                                          self.workspace, self.derived)
            try:
                states = rk(t0, times[:1] if trial else times, x)
            except Interrupted as interrupted:  # as a NamedCall's: outputs by name
                done = getattr(interrupted, "outputs", None)
                if done is not None:
                    interrupted.outputs = {"xf": done, "zf": loop_algebraic(
                        self.loops, times, done, self.solved)}
                raise
            self.steps += rk.last.accepted
            return states, loop_algebraic(self.loops, times, states, self.solved)
        if not system.n_cut:
            integrator = self._cvodes(t0, times, trial)
            out = integrator(x0=x)
        else:
            integrator = self._idas(t0, times, x, z, times[-1] - t0 if trial else None)
            out = integrator(x0=x, z0=z, p=self.loops.mask)
        self.steps += _steps(integrator, x, z, self.loops.mask if system.n_cut else ())
        states = out["xf"]
        algebraic = out["zf"] if system.n_cut else np.zeros((0, len(times)))
        if not nonfinite.all_finite(states, algebraic):
            raise RuntimeError("the state became NaN or infinite")
        return states, algebraic

    def _cvodes(self, t0: float, times, trial: bool) -> NamedCall:
        """CVODES over the grid, kept for a later run over the same grid with the same options
        (docs/decisions/joint-run-fixed-costs.md), to times[0] only for a `trial` point (not
        kept); its problem: runtime.functional_ode's."""
        from casmech.runtime import functional_ode

        functional = self.options["nonlinear_solver_iteration"] == "functional"
        if trial:
            return NamedCall(ca.integrator("joint", "cvodes", functional_ode.problem(
                self.system, functional), t0, list(times[:1]), self.options))
        return self._kept("cvodes", (functional,), lambda: functional_ode.problem(
            self.system, functional), t0, times, lambda: self.options)

    def _idas(self, t0: float, times, x, z, first: float | None) -> NamedCall:
        """IDAS over the grid from (t0, x, z); its options depend on that state (_dae_options),
        so it is kept for a later run from the same state over the same grid (a repeated
        run: its start is kept too, runtime.joint_dynamics._start)."""
        return self._kept("idas", (np.asarray(x).tobytes(), np.asarray(z).tobytes(), first),
                          lambda: self.system.problem, t0, times,
                          lambda: self.options | self._dae_options(t0, times, x, z, first))

    def _kept(self, plugin: str, key: tuple, problem, t0: float, times, options) -> NamedCall:
        """casadi's `plugin` integrator of problem() over the grid with options(), kept in the
        workspace by `key`, the system's ODE or DAE (the workspace may hold the joint systems
        of several compile settings), the start and grid and self.options, and called through
        a buffer (runtime.buffers.NamedCall)."""
        key = (*key, self.system.dynamics, float(t0), np.asarray(times, float).tobytes(),
               self._key())
        return self.workspace.kept(plugin, key, lambda: NamedCall(
            ca.integrator("joint", plugin, problem(), t0, list(times), options())))

    def _key(self) -> tuple:
        """self.options as a key (final by the first solver call)."""
        if self._options_key is None:
            self._options_key = tuple(sorted(self.options.items()))
        return self._options_key

    def _dae_options(self, t0, times, x, z, first: float | None = None) -> dict:
        """IDAS's options for the loops' DAE, as runtime.dynamics sets them for GGL: the r-p
        rule's first step, the algebraic unknowns out of the error test and held in Newton's
        test per group (algebraic_tolerances; docs/decisions/algebraic-tolerances.md).
        `first`: the interval the first step is sized by (default the first output interval)."""
        from casmech.formulations.dae_options import algebraic_tolerances, initial_step

        system = self.system
        x_dot = np.array(system.dynamics(t0, x, z, self.loops.mask)[0].full()).ravel()
        nb = len(system.tree.joints)  # every body is the child of one tree joint
        q, _, q_ddot, _ = (np.array(v.full()).ravel()
                           for v in system.motion(t0, x, z, np.ones(nb)))
        n = 3 * nb
        settings = self.settings
        step0 = settings.initial_step or initial_step(
            q[:n], q_ddot[:n], self.options["reltol"], self.options["abstol"],
            first or times[0] - t0)
        return {"suppress_algebraic": True, "calc_ic": False, "init_xdot": list(x_dot),
                "step0": step0,
                "abstolv": [self.options["abstol"]] * len(x) + list(algebraic_tolerances(
                    self.options["reltol"], settings.algebraic_tolerance, np.zeros(0),
                    z[:system.n_cut], len(z), settings.mu_tolerance))}


def _steps(integrator: NamedCall, *inputs) -> int:
    """The steps of `integrator`'s last call, from `inputs`: its statistics, read once per
    inputs (a kept integrator is deterministic: a call from the inputs of the call before it
    takes the steps that one took), kept in its `derived`."""
    key = b"".join(np.asarray(a, float).tobytes() for a in inputs)
    last = integrator.derived
    if last is None or last[0] != key:
        integrator.derived = last = key, int(integrator.stats().get("nsteps", 0))
    return last[1]


def choose_method(system: JointSystem, t0: float, x0, step: float, forces: bool = True,
                  settings: DynamicsSolver = DEFAULT, workspace: Workspace | None = None,
                  capped: bool = False, in_c=lambda: True) -> tuple[str, float | None]:
    """(method, the spectral radius at t0 or None where not examined) of method auto: "bdf" when
    the tree's ODE is stiff at t0 (settings.stiff_threshold), else "dop853", or "adams" where
    the step is `capped` (contacts, stops: runtime.contact_steps; an explicit method's every
    step would cost its 12 evaluations) or DOP853 would not run in C (`in_c()` False, asked only
    when an explicit method is chosen: runtime.dop853.in_c, not for an interpreted bundle's SX,
    a mapped tree's MX graph or without a C compiler), where its 12 evaluations a step in
    CasADi's virtual machine cost more than CVODES's Adams. Loops: "dop853" (their projected
    ODE, compiled with a compiled bundle: runtime.projected_loops) in C without force elements
    and capped steps, else "adams" (their DAE goes to IDAS, which no stiffness of theirs can
    stall).

    Without force elements (`forces` False: gravity, drivers and inertia only) the ODE has no
    source of stiffness: its eigenvalues are pendulum and gyroscopic frequencies, which the
    solution follows, so it is not examined. The spectral radius at (t0, x0)
    (runtime.stiffness) depends on the system and the start alone: kept in `workspace`;
    under DOP853 it bounds the step (runtime.stiffness.stable_step).
    docs/decisions/method-auto.md."""
    def explicit() -> str:
        return "adams" if capped or not in_c() else "dop853"

    if system.n_cut:
        return ("adams" if forces else explicit()), None
    if not forces or not 0 < len(x0) <= settings.stiff_states:
        return explicit(), None  # (compiled_system compiles the derivative this needs up to
        #                           this size)
    from casmech.runtime.stiffness import spectral_radius

    x0 = np.asarray(x0, float)
    radius = spectral_radius(system, t0, x0) if workspace is None else workspace.kept(
        "stiffness", (system.dynamics, float(t0), x0.tobytes()),
        lambda: spectral_radius(system, t0, x0))
    if radius is None:
        return explicit(), None
    return ("bdf" if radius * step > settings.stiff_threshold else explicit()), radius


def _start(functions: SystemFunctions, system: JointSystem, t0: float,
           settings: Assembly, workspace: Workspace):
    """(x, z, loops, signs) of a run from t0: the file's state assembled (runtime.assembly),
    mapped to joint coordinates, the loops' consistent multipliers and the quaternion signs;
    a function of the bundle, its joint system, t0 and the assembly settings alone, so kept in
    the workspace (arrays read-only)."""
    return _kept_start(functions, system, t0, settings, workspace)[:4]


def _kept_start(functions: SystemFunctions, system: JointSystem, t0: float,
                settings: Assembly, workspace: Workspace):
    """_start's (x, z, loops, signs) and a dict of what runs from it derive, filled by the
    first run that needs each entry and found by plain keys, no CasADi Function hashed (the
    rows at t0 and the Recorder: runtime.joint_recorder; the loops' ODE and DOP853:
    runtime.projected_loops)."""
    def build():
        q0, q_dot0 = assembly.initial_state(functions, t0, settings, workspace)
        x = initial_state(system, q0, q_dot0)
        loops = Loops(system, t0, x, settings)
        z = loops.z(t0, x)
        signs = quaternion_signs(system, t0, x, z, q0, functions.n_bodies)
        for array in (x, z, signs, loops.mask):
            array.setflags(write=False)
        return x, z, loops, signs, {}

    return workspace.kept("joint_starts", (float(t0), settings, system.dynamics), build)


def run_joint_dynamics(functions: SystemFunctions, t_end: float, step: float, rtol: float,
                       atol: float, t0: float = 0.0, progress=None,
                       method: str = METHOD, extra_events=(),
                       settings: DynamicsSolver = DEFAULT,
                       workspace: Workspace | None = None) -> Result:
    """The model's `events:` and `extra_events` (runtime.events.Event) are located and
    recorded in Result.events; without any, no event work is done (runtime.joint_run)."""
    return prepare(functions, t_end, step, rtol, atol, t0, method, settings,
                   workspace).run(functions, progress, extra_events)


def prepare(functions: SystemFunctions, t_end: float, step: float, rtol: float, atol: float,
            t0: float = 0.0, method: str = METHOD, settings: DynamicsSolver = DEFAULT,
            workspace: Workspace | None = None) -> JointRun:
    """A run over the output grid from t0 to t_end by step, prepared (runtime.joint_run): the
    joint system and the kept start of the workspace, method auto's choice from that start,
    the Recorder, the integrator with its options; a function of the bundle and these
    arguments alone, so a JointRun serves every later run of the same arguments on this
    workspace."""
    workspace = of(functions, workspace)
    system = joint_system(functions, settings, workspace)
    x, z, loops, signs, derived = _kept_start(functions, system, t0, settings.assembly,
                                              workspace)
    step_options = contact_steps.options(functions.ir, step, t_end - t0, settings)
    if method == "auto":
        method, radius = choose_method(
            system, t0, x, step, bool(functions.ir.forces or functions.ir.motors), settings,
            workspace, "max_step_size" in step_options,
            lambda: workspace.kept("dop853_in_c", system.dynamics,
                                   lambda: dop853.in_c(system.dynamics, not system.n_cut)))
        if method == "dop853" and radius is not None:  # the fastest mode damped, not met;
            from casmech.runtime.stiffness import stable_step

            step_options["max_step_size"] = stable_step(radius)  # outputs without the
            step_options[dop853.FREE_OUTPUTS] = True  # interpolant's evaluations where it may
    recorder = Recorder.kept(derived, functions, system, signs, loops.mask, workspace,
                             settings.loop_rows == "solved" or method == "dop853")
    integrate = _Integrator(system, loops, rtol, atol, method, workspace, settings)
    integrate.derived = derived
    if method == "dop853" and system.n_cut:  # the loops' projected ODE (runtime.projected_loops)
        integrate.loop = loop_ode_of(functions, system, loops.mask, workspace, derived)
        integrate.solved = recorder.loops is not None
    integrate.options |= step_options
    tree = system.tree
    names = (tuple(j.name or f"free '{functions.body_names[j.child]}'" for j in tree.joints),
             tuple(j.name for j in tree.cut))
    return JointRun((x, z, loops, derived), recorder, integrate, output_times(t0, t_end, step),
                    rtol, atol, settings, workspace, names,
                    events.model_events(functions, workspace))
