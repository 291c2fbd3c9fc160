"""Many runs of a study in one call: the parametric library's tree ODE integrated by CVODES,
mapped over parameter sets (casadi's map, on threads where the caller has cores).

A study is batched (study.sweep.prepare, mode "batched", or auto from COMPILE_RUNS runs) when
`obstacle` finds nothing against it: dynamics of a tree in joint coordinates with no events,
contacts or stops, the method fixed for every run (adams or bdf given, or auto with no force
element: Adams; a study asking dop853 runs run by run, runtime.dop853),
no `initial:` values, no `--full`, the parametric library applies, and the study's parameters
can be symbolic (optimal.system.traced_model) with the library's structure and model data at
the design's corners (so the values there are checked by the schema as a run's are).

Per run, instead of loading the model at its values: theta -> the model data d(theta) (the
lowering traced once, model.parametric), the file's pose and velocities from d, the pose
checked against the constraints as assembly checks it (a run whose pose assembly would move
is made the ordinary way), the velocities projected onto them as assembly projects them,
mapped to joint coordinates; then CVODES on
the library's joint_ode over the output grid (chunks of the options' joint_chunk
intervals, as a run restarts), and the results columns the kept outputs read (the row of
fmu.outputs over d) from the library's joint_motion, for every run of the chunk in one call.
A chunk whose call fails, or a run with a value that is not finite, is made again run by run
(runner.Runner), so failures carry their own reasons. `wall_s` of a batched run is its
share of its chunk's time.
"""

from __future__ import annotations

import functools
import itertools
import time
from collections.abc import Mapping, Sequence

import casadi as ca
import numpy as np

from casmech.errors import CasmechError
from casmech.runtime import cancel, interrupts
from casmech.study import kept as kept_outputs
from casmech.study.runner import Job, Outcome, run_batch, runner_for

CORNERS = 64  # at most this many corners of the design's box are checked, else no batch
RUNS_PER_CALL = 256  # runs per mapped call (memory of the output grid; Ctrl-C between calls)
SAME_DATA = 1e-12  # relative difference allowed between traced and lowered model data


def corners(points: Sequence[Mapping[str, float]], names: Sequence[str]) -> list[dict]:
    """The corners of the box of the points' values (each parameter's lowest and highest)."""
    bounds = [sorted({min(p[n] for p in points), max(p[n] for p in points)}) for n in names]
    return [dict(zip(names, values, strict=True)) for values in itertools.product(*bounds)]


def obstacle(model, settings, study, full: bool) -> str | None:
    """Why this study cannot run batched, or None (module docstring); `settings` the checked
    analysis settings (runtime.analyses.analysis_settings), `study` a design.Study."""
    from casmech.backends import codegen, parametric
    from casmech.formulations.joint_system import layout
    from casmech.formulations.tree import spanning_tree
    from casmech.model.lower import lower
    from casmech.runtime import contact_steps

    ir = lower(model)
    tree = spanning_tree(ir)
    method = getattr(settings.options, "method", "auto")
    reasons = (
        (full, "--full keeps every run's whole table"),
        (not (codegen.available() and parametric.applies(model)), "no parametric library"),
        (settings.type != "dynamics", f"analysis type {settings.type}"),
        (getattr(settings.options, "formulation", "auto") not in ("auto", "joint"),
         "a formulation other than joint coordinates"),
        (not tree.is_tree, "closed loops"),
        (tree.is_tree and layout(tree).n_x == 0, "no free coordinate to integrate"),
        (bool(settings.events) or any(k.reduction == "event" for k in map(
            kept_outputs.parse, study.keep)), "events"),
        (contact_steps.max_step(ir, settings.output_step, settings.t_end) is not None,
         "contacts or joint stops"),
        (method == "auto" and bool(ir.forces or ir.motors),
         "method auto examines each run's stiffness"),
        (method == "dop853", "method dop853 integrates each run by itself (a batch maps "
         "CVODES)"),
        (any(joint.initial for joint in ir.joints), "joints' initial: values"))
    found = next((why for bad, why in reasons if bad), None)
    return found or _structure_obstacle(model, study)


def _structure_obstacle(model, study) -> str | None:
    """The traced lowering against the library's at the model's values and the corners."""
    from casmech.model import parametric
    from casmech.model.lower import lower
    from casmech.optimal.system import parametric_system
    from casmech.schema import load_model_text

    names = study.parameters
    try:
        system = parametric_system(model, names)
    except CasmechError as error:
        return f"a parameter cannot be traced ({str(error).splitlines()[0]})"
    points = study.points()
    box = corners(points, names)
    if len(box) > CORNERS:
        return f"{len(box)} corners of the design to check"
    for values in [None, *box]:
        try:
            at = model if values is None else load_model_text(
                model.text, model.file, {**model.overrides, **{
                    k: repr(float(v)) for k, v in values.items()}})
        except CasmechError as error:
            return f"the model at {values}: {str(error).splitlines()[0]}"
        lowered, signature = parametric.data(lower(at))
        theta = system.values if values is None else [values[n] for n in names]
        traced = np.array(system.data(theta).full()).ravel()
        if signature != system.split.signature or not np.allclose(
                traced, lowered, rtol=SAME_DATA, atol=SAME_DATA * max(1.0, np.abs(lowered).max(
                    initial=0.0))):
            return f"the model's structure changes at {values or 'its values'}"
    return None


class Batch:
    """One process's batched runs of a job (built once: batch_for)."""

    def __init__(self, job: Job, parameters: tuple[str, ...]):
        from casmech import backends
        from casmech.backends import codegen
        from casmech.formulations.registry import FORMULATIONS
        from casmech.formulations.tree import spanning_tree
        from casmech.optimal.system import parametric_system
        from casmech.runtime.analyses import analysis_settings
        from casmech.runtime.joint_dynamics import METHODS
        from casmech.runtime.kinematics import output_times
        from casmech.runtime.results import column_names
        from casmech.schema import load_model_text

        self.job, self.parameters = job, parameters
        model = load_model_text(job.text, file=job.file, overrides=dict(job.base))
        nominal = backends.compile(model, "compiled")
        settings = analysis_settings(nominal, **dict(job.settings))
        self.system = parametric_system(model, parameters)
        self.library, _ = codegen.parametric_functions(model)
        self.tree = spanning_tree(nominal.ir)
        self.n_x = len(FORMULATIONS["joint"].states(nominal).differential)
        self.n_bodies = nominal.n_bodies
        self.times = np.asarray(output_times(0.0, settings.t_end, settings.output_step), float)
        solver = settings.options.solver
        self.chunk = solver.joint_chunk
        self.tolerance = solver.assembly.tolerance
        method = getattr(settings.options, "method", "auto")
        self.options = {"reltol": settings.rtol, "abstol": settings.atol,
                        "max_num_steps": solver.max_steps, "disable_internal_warnings": True,
                        **METHODS["adams" if method == "auto" else method]}
        self.kept = [kept_outputs.parse(text) for text in job.keep]
        every = column_names(nominal)
        self.columns = sorted({every.index(k.column) for k in self.kept} - {0})
        self.names = ["t", *(every[k] for k in self.columns)]
        self.moving = bool(nominal["nu"].sparsity_out(0).nnz())  # drivers: velocities solved
        self._start = self._start_function()
        self._rows = {}  # rows per run -> the mapped rows' function
        self._maps = {}  # (what, runs, ...) -> its mapped function, called through buffers

    def _mapped(self, key: tuple, make):
        """A mapped function, made once per key and called with NumPy arrays in and out."""
        from casmech.runtime.buffers import BufferedCall, NamedCall

        if key not in self._maps:
            function = make()
            self._maps[key] = (NamedCall if key[0] == "integrator" else BufferedCall)(function)
        return self._maps[key]

    # ------------------------------------------------------------------ per-run start
    def _start_function(self) -> ca.Function:
        """theta -> (d, joint data, q0, file velocities, |phi| at t0, relative states)."""
        s, lib = self.system, self.library
        theta = ca.MX.sym("theta", len(self.parameters))
        d = s.data(theta)
        data = lib["joint_data"](d)
        q = s["initial_guess"](theta)
        q_dot = s["file_velocities"](q, theta)
        phi = s["phi"](0.0, q, theta)
        rotations, gaps, twists = lib["joint_relative_states"](q, q_dot, data)
        worst = ca.mmax(ca.fabs(phi)) if phi.numel() else ca.MX(0)
        return ca.Function("batch_start", [theta], [d, data, q, q_dot, worst, rotations,
                                                     gaps, twists])

    def start(self, theta: np.ndarray):
        """Per run (columns): d, joint data, q0, x0 and which runs need the ordinary path
        (a pose assembly would move). Velocities are the file's projected onto the
        constraints as runtime.assembly.solve_velocities projects them."""
        n = theta.shape[1]
        d, data, q, q_dot, worst, rotations, gaps, twists = self._mapped(
            ("start", n), lambda: self._start.map(n))(theta)
        ordinary = ~(worst.ravel() <= self.tolerance)  # assembly would move the pose
        solved = np.flatnonzero(~ordinary & (self.moving | np.any(q_dot != 0, axis=0)))
        if len(solved):  # least squares per run, then their relative states again
            q_dot = q_dot.copy()
            for i in solved:
                q_dot[:, i] = self._projected(theta[:, i], q[:, i], q_dot[:, i])
            relative = self.library["joint_relative_states"]
            again = self._mapped(("relative", len(solved)), lambda: relative.map(len(solved)))(
                q[:, solved], q_dot[:, solved], data[:, solved])
            nj = len(self.tree.joints)
            for array, found, width in zip((rotations, gaps, twists), again, (3, 1, 1),
                                           strict=True):
                for j, i in enumerate(solved):
                    array[:, width * nj * i:width * nj * (i + 1)] = \
                        found[:, width * nj * j:width * nj * (j + 1)]
        return d, data, q, self._joint_states(~ordinary, rotations, gaps, twists), ordinary

    def _projected(self, theta, q, q_dot) -> np.ndarray:
        """Phi_q q_dot = nu, closest (least squares) to the file's q_dot."""
        from casmech.numerics import numeric_qr

        phi_q = self.system["phi_q"](0.0, q, theta)
        nu = np.array(self.system["nu"](0.0, q, theta).full()).ravel()
        residual = nu - np.array(ca.mtimes(phi_q, ca.DM(q_dot))).ravel()
        return q_dot + numeric_qr.lstsq(phi_q, residual)

    def _joint_states(self, chosen, rotations, gaps, twists) -> np.ndarray:
        """x0 of the chosen runs from their joints' relative states (the joint formulation's
        start, formulations.joint_start.from_relative, per run)."""
        from casmech.formulations.joint_start import from_relative

        nj = len(self.tree.joints)
        x0 = np.zeros((self.n_x, len(chosen)))
        for i in np.flatnonzero(chosen):
            x0[:, i] = from_relative(self.tree, rotations[:, 3 * nj * i:3 * nj * (i + 1)],
                                     gaps[:, nj * i:nj * (i + 1)], twists[:, nj * i:nj * (i + 1)])
        return x0

    # ------------------------------------------------------------------ the mapped runs
    def _rows_function(self, rows: int) -> ca.Function:
        """(t row, X, q0, joint data, d) of one run -> its kept columns at every row: the
        quaternion signs as runtime.joint_dynamics takes them, the library's joint_motion and
        fmu.outputs' row over d, mapped over the rows."""
        if rows in self._rows:
            return self._rows[rows]
        from casmech.equations.functions import build_functions
        from casmech.fmu import outputs

        split, nb, lib = self.system.split, self.n_bodies, self.library
        bundle = build_functions(split.ir, split.symbols)
        t = ca.SX.sym("t")
        n = bundle.n_coordinates
        q, q_dot, q_ddot = (ca.SX.sym(name, n) for name in ("q", "q_dot", "q_ddot"))
        lam = ca.SX.sym("lam", bundle.n_rows)
        row = outputs.row(bundle, t, q, q_dot, q_ddot, lam, split.symbols, split.symbols)
        picked = ca.vertcat(*(row[k - 1] for k in self.columns)) if self.columns else ca.SX(0, 1)
        kept = ca.Function("kept_row", [t, q, q_dot, q_ddot, lam, split.symbols], [picked])
        motion = lib["joint_motion"]
        times, states = ca.MX.sym("t", 1, rows), ca.MX.sym("x", self.n_x, rows)
        q0, data = ca.MX.sym("q0", 7 * nb), ca.MX.sym("data", motion.size1_in(4))
        d = ca.MX.sym("d", split.symbols.numel())
        z = ca.MX(0, 1)
        first = motion(times[0], states[:, 0], z, ca.DM.ones(nb), data)[0]
        signs = ca.vertcat(*(ca.if_else(ca.dot(first[3 * nb + 4 * k:3 * nb + 4 * k + 4],
                                                q0[3 * nb + 4 * k:3 * nb + 4 * k + 4]) < 0,
                                         -1, 1) for k in range(nb)))
        mapped = motion.map("motion_rows", "serial", rows, [2, 3, 4], [])
        columns = mapped(times, states, z, signs, data)
        values = kept.map("kept_rows", "serial", rows, [5], [])(times, *columns, d)
        self._rows[rows] = ca.Function("batch_rows", [times, states, q0, data, d], [values])
        return self._rows[rows]

    def _integrate(self, x0: np.ndarray, data: np.ndarray, threads: int) -> np.ndarray:
        """States of every run at every output time, (n_x, runs, rows): CVODES over the
        library's joint_ode with the run's joint data as its p, mapped over the runs, one call
        per chunk of the grid."""
        ode, (n_x, n) = self.library["joint_ode"], x0.shape
        t, x, p = ca.MX.sym("t"), ca.MX.sym("x", n_x), ca.MX.sym("p", ode.size1_in(2))
        problem = {"t": t, "x": x, "p": p, "ode": ode(t, x, p)}
        blocks, state, k = [x0[:, :, None]], x0, 0
        while k < len(self.times) - 1:
            grid = self.times[k + 1:k + 1 + self.chunk]

            def make(k=k, grid=grid):
                integrator = ca.integrator("batch", "cvodes", problem, float(self.times[k]),
                                           list(grid), self.options)
                return integrator.map(n, "thread", threads) if threads > 1 else \
                    integrator.map(n)

            out = self._mapped(("integrator", k, n, threads), make)(x0=state, p=data)["xf"]
            out = out.reshape(n_x, n, len(grid))
            blocks.append(out)
            state, k = out[:, :, -1], k + len(grid)
        return np.concatenate(blocks, axis=2)

    def run(self, points: Sequence[Mapping[str, float]], threads: int = 1) -> list[Outcome]:
        """Every point's Outcome; the runs the batch cannot make are made by runner.Runner."""
        clock = time.perf_counter()
        theta = np.array([[float(p[n]) for n in self.parameters] for p in points]).T
        d, data, q0, x0, ordinary = self.start(theta.reshape(len(self.parameters), -1))
        outcomes: list[Outcome | None] = [None] * len(points)
        chosen = np.flatnonzero(~ordinary)
        if len(chosen):
            with cancel.solving():
                try:
                    states = self._integrate(x0[:, chosen], data[:, chosen], threads)
                except RuntimeError as error:  # a run failed: every run the ordinary way
                    interrupts.check(error)
                    chosen = np.zeros(0, int)
            if len(chosen):
                rows = len(self.times)
                n = len(chosen)
                (values,) = self._mapped(("rows", n, threads), lambda: self._rows_function(
                    rows).map(n, "thread", max(threads, 1)))(
                    np.tile(self.times, n), states.reshape(states.shape[0], -1), q0[:, chosen],
                    data[:, chosen], d[:, chosen])
                share = (time.perf_counter() - clock) / len(points)
                for j, i in enumerate(chosen):
                    table = np.vstack([self.times, values[:, j * rows:(j + 1) * rows]]).T
                    if not np.all(np.isfinite(table)) or not np.all(np.isfinite(states[:, j])):
                        continue  # made the ordinary way: its failure and reason
                    outcomes[i] = Outcome(dict(points[i]), "complete", wall_s=share,
                                          kept=kept_outputs.values(self.kept, self.names, table),
                                          rows=rows)
        runner = runner_for(self.job)
        for i, outcome in enumerate(outcomes):
            if outcome is None:
                outcomes[i] = runner.run(points[i])
        return outcomes


@functools.lru_cache(maxsize=2)
def batch_for(job: Job, parameters: tuple[str, ...]) -> Batch:
    """The process's batch of a job, built on first use."""
    return Batch(job, parameters)


def run_points(job: Job, points: Sequence[Mapping[str, float]], threads: int = 1
               ) -> list[Outcome]:
    """A task of a study: its points batched when the job says so (on `threads` threads),
    else run by run (runner.run_batch); a batch that raises what it does not record is made
    run by run."""
    if not job.batched:
        return run_batch(job, list(points))
    try:
        return batch_for(job, job.batched).run(points, threads)
    except Exception as error:  # noqa: BLE001  (KeyboardInterrupt is not one)
        interrupts.check(error)
        return run_batch(job, list(points))
