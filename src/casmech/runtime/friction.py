"""Dynamics of a model with joint friction (or exact contact friction): sliding and stuck modes
switched at located events (docs/decisions/joint-friction.md, contact-friction.md).

A run is a sequence of segments, each an ordinary dynamics run (any formulation) of the model
with every friction joint in one mode, from the state the previous segment ended in:

- sliding (+1 or -1): the friction law with that sign fixed (equations/friction.py), smooth
  over the segment; an event stops it where the joint's rate reaches 0;
- stuck (0): the law off and a driver row holding the joint's coordinate at its value, the
  row's multiplier the holding force; an event stops it where |holding force| reaches the
  static limit.

At a stop a joint whose rate reached 0 is tried stuck and a stuck one past its limit slips
against its holding force; before a segment runs, its start is checked on a short step, and
while a stuck joint's holding force there exceeds its static limit, the one furthest past it
slides against that force (one by one: releasing one changes what the others need).
Segments start from the ending state (the bodies' initial poses and velocities of a lowered
model), so each is a bundle of its own; the rows keep the run's output grid (a segment
starting between grid points runs to the next one first) with each switch's row added, and
the switches are `Result.metadata["friction_switches"]`.

The points of contacts with exact friction are switched by the same loop, as units of their
own (runtime/contact_friction.py: their modes, rows, events and holding forces).
"""

from __future__ import annotations

from dataclasses import replace

import casadi as ca
import numpy as np

from casmech.core import euler
from casmech.core.expressions import parse
from casmech.elements.joint_types import COORDINATES
from casmech.equations import friction, friction_load
from casmech.equations.functions import build_functions
from casmech.equations.symbols import Coordinates
from casmech.errors import AnalysisError
from casmech.runtime import assembly, contact_friction, events
from casmech.runtime.kinematics import output_times
from casmech.runtime.results import Result, table
from casmech.schema.resolved import ScalarFunction

SWITCHES = 100_000  # mode switches a run may make (a Zeno cascade ends the run there)
COUNTERS = ("steps", "idas_steps", "idas_calls", "event_probes", "projections")  # summed
SLACK = 1e-9  # a holding force this far (relative) past the static limit still holds
STILL = 1e-9  # |rate| (SI) at or below which a joint starting a run is tried stuck


def on_driven(ir) -> list:
    """The friction elements (ir.limits holds them after the stops) on a driven coordinate (a
    `driver:`, a position or speed motor): the sliding law by the prescribed rate's sign,
    never stuck (the driver holds it); their load parts: runtime/driven_friction.py."""
    driven = {(j.name, key) for j in ir.joints for key in j.drivers}
    return [e for e in ir.limits if e.type in friction.COORDINATE
            and (e.name, friction.COORDINATE[e.type]) in driven]


def elements(ir) -> list:
    """The friction elements whose modes a run switches: those of joints whose coordinate is
    free and with a Coulomb or static part (`on_driven`: the others)."""
    held = {e.name for e in on_driven(ir)}
    return [e for e in ir.limits if e.type in friction.COORDINATE
            and e.name not in held and not _smooth(e)]


def switched(ir) -> bool:
    """Whether a dynamics run of the model switches modes: joint friction with a Coulomb or
    static part, or contacts with exact friction (runtime/contact_friction.py)."""
    return bool(elements(ir) or contact_friction.elements(ir))


def _smooth(element) -> bool:
    """A purely viscous friction (no Coulomb or static part): smooth, no modes."""
    p = element.params
    return all(isinstance(p[k], (int, float)) and p[k] == 0
               for k in ("coulomb", "static", "mu", "mu_static"))


def loaded(element) -> bool:
    """Whether a friction element has a load part (its limits depend on the multipliers)."""
    return not (isinstance(element.params["mu_static"], (int, float))
                and element.params["mu_static"] == 0)


def _coordinates(ir) -> ca.Function:
    """(q, q_dot) -> (s, s_dot) of every friction joint."""
    x = Coordinates.create(ir.n_bodies)
    s = [friction.coordinate(e, x) for e in elements(ir)]
    values = x.ground_fixed(ca.vertcat(*s, *(x.rate(v) for v in s)))
    return ca.Function("friction_coordinates", [x.q, x.q_dot], [values])


def segment_model(ir, q, q_dot, modes: dict, values: dict):
    """(the model of a segment, the row index of each stuck joint): the bodies start at
    (q, q_dot), each friction joint in its mode (+1, -1 sliding, 0 stuck at `values`)."""
    n = ir.n_bodies
    bodies = []
    for k, body in enumerate(ir.bodies):
        p, p_dot = q[3 * n + 4 * k:3 * n + 4 * k + 4], q_dot[3 * n + 4 * k:3 * n + 4 * k + 4]
        omega = 2 * np.asarray(euler.e_matrix(ca.DM(p)) @ ca.DM(p_dot)).ravel()
        bodies.append(replace(body, r0=q[3 * k:3 * k + 3].copy(), p0=p.copy(),
                              r_dot0=q_dot[3 * k:3 * k + 3].copy(), omega0=omega))
    limits = tuple(replace(e, params=dict(e.params) | {
        "direction": float(modes[e.name]), "stuck": float(modes[e.name] == 0)})
        if e.name in modes and e.type in friction.COORDINATE else e for e in ir.limits)
    kinds = {e.name: friction.COORDINATE[e.type] for e in elements(ir)}
    primitives, joints, rows = [], [], {}
    for joint in ir.joints:
        own = [ir.primitives[r] for r in joint.rows]
        drivers = dict(joint.drivers)
        if modes.get(joint.name, 1) == 0:
            key = kinds[joint.name]
            kind, template, label = COORDINATES[key].driver
            held = ScalarFunction("s0", parse("s0"), {"s0": float(values[joint.name])}, ("t",))
            info = replace(own[0].row, kind=kind, label=f"friction '{joint.name}': stuck")
            own.append(replace(own[0], kind=kind, vectors={k: joint.geometry[v] for k, v in
                                                             template.items()},
                               f=held, offset=0.0, is_driver=True, row=info, others=()))
            drivers[key] = held
            rows[joint.name] = len(primitives) + len(own) - 1
        joints.append(replace(joint, rows=range(len(primitives), len(primitives) + len(own)),
                              drivers=drivers, initial={}, initial_sources={}))
        primitives += own
    return replace(ir, bodies=tuple(bodies), primitives=tuple(primitives), joints=tuple(joints),
                   limits=limits, reference_pose=None), rows


def _events(functions, switched: list, modes: dict, rows: dict) -> list:
    """The stop events of a segment: a sliding joint's rate reaching 0, a stuck one's holding
    force reaching the static limit (with a load part: Ts + mu_static L, L of the multipliers).
    `switched`: the base model's elements (a stuck joint's coordinate is driven in the
    segment's)."""
    x = Coordinates.create(functions.ir.n_bodies)
    lam = ca.SX.sym("lam", functions.n_rows)
    found = []
    for e in switched:
        mode = modes[e.name]
        if mode == 0:
            value = ca.fabs(lam[rows[e.name]]) - e.params["static"]
            if loaded(e):
                value -= e.params["mu_static"] * friction_load.normal(functions, e)(
                    x.t, x.q, x.q_dot, lam)
            direction = "rising"
        else:
            value = x.rate(friction.coordinate(e, x))
            direction = "falling" if mode > 0 else "rising"
        function = ca.Function("friction", [x.t, x.q, x.q_dot, x.q_ddot, lam],
                               [x.ground_fixed(ca.SX(value))])
        found.append(events.Event(f"{e.name}.friction", function, direction, "stop"))
    return found


class _Run:
    """One friction run: its segments joined into one Result over the base bundle."""

    def __init__(self, functions, settings, progress, segment):
        self.functions, self.ir, self.segment = functions, functions.ir, segment
        self.settings = settings
        self.result = Result("dynamics", on_row=progress)
        self.result.event_states = Result("events")
        self.names = [e.name for e in elements(self.ir)]
        self.contacts = contact_friction.Contacts(self.ir)
        self.coordinates = _coordinates(self.ir)
        self.switches: list[dict] = []
        self.fixed = {f"{n}.{c}": [] for n in self.names for c in friction.COLUMNS}
        self.fixed |= {f"{f.name}.friction_force": [] for f in self.contacts.forces}
        self.segments = 0
        self.loads = None  # (the last built segment's load system, its joints) or None

    def values(self, q, q_dot) -> tuple[dict, dict]:
        out = np.array(self.coordinates(q, q_dot)).ravel()
        k = len(self.names)
        return dict(zip(self.names, out[:k], strict=True)), dict(zip(self.names, out[k:],
                                                                      strict=True))

    def build(self, t, q, q_dot, modes):
        """The bundle of a segment from (q, q_dot) at t in `modes`, its events, the stuck
        joints' rows, the stuck contact points' row pairs. The sliding joints with load parts
        get their laws' loads (friction_load.sliding, solved together) from the segment's
        model without them."""
        from casmech.runtime.load_checks import check_loads

        s, _ = self.values(q, q_dot)
        ir, rows = segment_model(self.ir, q, q_dot, modes, s)
        ir, held = self.contacts.segment(ir, t, q, q_dot, modes)
        functions = build_functions(ir)
        sliding = [e for e in elements(ir) if loaded(e) and modes[e.name] != 0]
        self.loads = None
        if sliding:
            load = friction_load.sliding(functions, sliding, [modes[e.name] for e in sliding])
            check_loads(t, sliding, np.array(load(t, q, q_dot)).ravel())
            parts = {e.name: friction_load.part(load, i) for i, e in enumerate(sliding)}
            self.loads = (load, sliding)
            ir = replace(ir, limits=tuple(replace(f, params=dict(f.params) | {
                "load": parts[f.name]}) if any(f is e for e in sliding) else f for f in ir.limits))
            functions = build_functions(ir)
        stops = _events(functions, elements(self.ir), modes, rows)
        return functions, stops + self.contacts.events(functions, modes, held), rows, held

    def attempt(self, span, built, extra):
        """A segment over span = (t0, t1, step) on a bundle of `build`: its Result."""
        functions, stops = built[:2]
        self.segments += 1
        return self.segment(functions, span, (*extra, *stops))

    def limits(self, functions, result, k=0) -> dict:
        """The static limit of each friction joint in row k of a segment's Result: Ts, plus
        mu_static L with a load part."""
        state = (result.times[k], result.q[k], result.q_dot[k], result.lam[k])
        return {e.name: e.params["static"] + (e.params["mu_static"] * float(
            friction_load.normal(functions, e)(*state)) if loaded(e) else 0.0)
            for e in elements(self.ir)}

    def hold(self, result, rows, name, k=0) -> float:
        """The friction force holding a stuck joint in row k (the driver row's multiplier
        acting along the coordinate)."""
        return -float(result.lam[k, rows[name]])

    def excess(self, built, start) -> dict:
        """{stuck joint or contact point: (|holding force| - its static limit, the limit, the
        modes it and what is held with it slip in)} at the first row of a segment's start check."""
        functions, _, rows, held = built
        limits = self.limits(functions, start)
        found = {n: (abs(self.hold(start, rows, n)) - limits[n], limits[n],
                     {n: -int(np.sign(self.hold(start, rows, n)))}) for n in rows}
        return found | self.contacts.excess(functions, held, start)

    def settle(self, span, q, q_dot, modes, extra):
        """The segment over span = (t0, t1, step) from (q, q_dot) in `modes`, with its stuck
        joints and contact points released one by one: while one's holding force at the start
        exceeds its static limit, the one furthest past it slides against that force (each
        start checked on a step of 1e-6 of the span before the segment runs). (modes, Result,
        bundle: Functions, events, the stuck joints' rows, the stuck points' rows)."""
        t0, t1, _ = span
        while True:
            built = self.build(t0, q, q_dot, modes)
            if built[2] or built[3]:
                tiny = 1e-6 * (t1 - t0)
                start = self.attempt((t0, t0 + tiny, tiny), built, extra)
                excess = self.excess(built, start)
                name = max(excess, key=lambda n: excess[n][0])
                over, limit, slip = excess[name]
                if over > SLACK * max(limit, 1.0):
                    modes = modes | slip
                    continue
            return modes, self.attempt(span, built, extra), built

    def run(self, t_end, step, extra) -> Result:
        from casmech.runtime.load_checks import check_loads

        t = 0.0
        q, q_dot = assembly.initial_state(self.functions, t, self.settings.options.solver.assembly)
        _, rates = self.values(q, q_dot)
        modes = {n: int(np.sign(r)) if abs(r) > STILL else 0 for n, r in rates.items()}
        modes |= self.contacts.start(t, q, q_dot)
        grid = output_times(0.0, t_end, step)
        first, fired, last = True, [], modes
        while t < t_end - 1e-12 * max(1.0, t_end):
            later = grid[grid > t + 1e-9 * step]
            t1 = t_end if np.isclose(t, grid, rtol=0, atol=1e-9 * step).any() else later[0]
            span = (t, t1, step if t1 == t_end else t1 - t)
            try:
                modes, found, built = self.settle(span, q, q_dot, modes, extra)
                if self.loads is not None:  # the loads solved at every row of the segment
                    load, sliding = self.loads
                    for k, time in enumerate(found.times):
                        check_loads(time, sliding, np.array(load(
                            time, found.q[k], found.q_dot[k])).ravel())
            except AnalysisError as error:  # a failure or an interrupt: the rows before it
                error.partial = self.finish()  # (of the segments done) in the base bundle's
                raise
            joints = [n for n in fired if n not in self.contacts.names]
            points = [n for n in self.contacts.names if self.label(n, modes[n]) !=
                      self.label(n, last[n])]  # a point's every change, a renewed slip none
            self.switches += [self.switch(t, name, modes) for name in joints + points]
            last = modes
            if first:
                self.result.metadata["friction_start_modes"] = {
                    n: self.label(n, m) for n, m in modes.items()}
            fired = [r.name.removesuffix(".friction") for r in found.events
                     if r.name.endswith(".friction") and r.action == "stop"
                     and r.t == found.times[-1]]
            self.keep(found, built, modes, first)
            first = False
            t, q, q_dot = found.times[-1], found.q[-1], found.q_dot[-1]
            if found.status == events.STOPPED and not fired:
                self.result.status = events.STOPPED  # a model's own stop event
                break
            if len(self.switches) >= SWITCHES:
                break
            modes = modes | self.contacts.renewed(modes, t, q, q_dot)
            for name in fired:  # a stuck joint slips against its holding force; a sliding
                # one whose rate reached 0 is tried stuck (settle releases it if it cannot be)
                modes = modes | self.stopped(name, modes[name], found, built)
        return self.finish()

    def stopped(self, name, mode, found, built) -> dict:
        """The new modes after a joint's or contact point's event stopped a segment."""
        if name in self.contacts.names:
            return self.contacts.stopped(name, mode, built[0], built[3], found)
        return {name: -int(np.sign(self.hold(found, built[2], name, -1))) if mode == 0 else 0}

    def label(self, name, mode):
        """A mode as metadata writes it (a joint's -1, 0, +1; a point's free, stuck,
        sliding)."""
        return contact_friction.label(mode) if name in self.contacts.names else mode

    def switch(self, t, name, modes) -> dict:
        """A switch of the run's list: {t, joint, mode} or {t, contact, mode}."""
        unit = "contact" if name in self.contacts.names else "joint"
        return {"t": float(t), unit: name, "mode": self.label(name, modes[name])}

    def keep(self, found, built, modes, first):
        """Append a segment's rows (without its first, the previous one's last) in the base
        bundle's multipliers, with the friction columns it computed."""
        functions, _, rows, held = built
        start = 0 if first else 1
        extra = sorted([*rows.values(), *contact_friction.rows_of(held)])
        kept = [k for k in range(found.lam.shape[1]) if k not in extra]
        names, values = table(functions, found)
        for name in self.names:
            for column in friction.COLUMNS:
                key = f"{name}.{column}"
                value = values[start:, names.index(key)].copy()
                if column == "friction" and modes[name] == 0:
                    value = -found.lam[start:, rows[name]]
                self.fixed[key].append(value)
        for key, value in self.contacts.friction_force(functions, held, found, start).items():
            self.fixed[key].append(value)
        self.result.fixed_columns = {k: np.concatenate(v) for k, v in self.fixed.items()}
        self.result.extend(found.times[start:], found.q[start:], found.q_dot[start:],
                           found.q_ddot[start:], found.lam[start:, kept])
        for record, k in zip(found.events, range(len(found.events)), strict=True):
            if record.name.removesuffix(".friction") in self.names + self.contacts.names:
                continue
            state = found.event_states
            self.result.events.append(record)
            self.result.event_states.extend([record.t], state.q[k:k + 1], state.q_dot[k:k + 1],
                                            state.q_ddot[k:k + 1], state.lam[k:k + 1, kept])
        counted = {k: self.result.metadata.get(k, 0) + v for k, v in found.metadata.items()
                   if k in COUNTERS and isinstance(v, int)}
        self.result.metadata.update(found.metadata | counted)

    def finish(self) -> Result:
        self.result.metadata.update(friction_switches=self.switches,
                                    friction_segments=self.segments)
        return self.result


def run(functions, settings, progress, segment, extra=()) -> Result:
    """A dynamics run of a model with joint friction; `segment(functions, (t0, t_end, step),
    events)` runs one segment (runtime.analyses)."""
    return _Run(functions, settings, progress, segment).run(settings.t_end, settings.output_step,
                                                            tuple(extra))
