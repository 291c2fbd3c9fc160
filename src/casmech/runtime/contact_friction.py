"""Exact Coulomb friction at the points of contact elements with `friction: {model: exact}`:
the units runtime/friction.py's run switches besides the joints
(docs/decisions/contact-friction.md).

Each point k of such an element is a unit `<contact>[k]` in one mode:

- "free" (apart at the segment's start): no friction; an event where its gap reaches 0;
- sliding, its mode the unit slip direction u0 at the start (a 3-tuple): -mu_d F_n v_t / |v_t|
  (elements/forces/contact.exact_friction; along u0 where v_t = 0); an event where v_t . u0
  reaches 0;
- "stuck": the law off, the point held by its Group's rows, and an event where its share of
  the holding force reaches mu_s F_n or its gap reaches 0 (the contact opens: it is free, the
  rest of its Group holds on).

The stuck points of one body pair on one plane (a box's corners, the feet of a stool, across
elements) form a Group held by three rows (two for a single point): two dp2 rows a . d_ij = 0
holding the material points at the points' centroid together along the plane (a_1, a_2 tangent
to the normal on body_i) and a dp1 row holding the turn about the normal. Three rows for the
three in-plane freedoms: per-point rows would be six or more, dependent while the body lies
flat and nearly dependent (not masked) once it pitches on the compliant normal. The rows'
multipliers give a force and a torque, shared by the points in proportion to their normal
forces (Contacts.holding), the share each point's slip test reads.

At a stop, a stuck point's Group slides (every point against its share: the body it held
moves); a sliding point is tried stuck when its slip speed is at or below SLIP_STOP (else it
slides on along its slip); a free one that touched slides along its slip, or is tried stuck
when it has none.
"""

from __future__ import annotations

from dataclasses import replace

import casadi as ca
import numpy as np

from casmech.core import euler
from casmech.core.records import record
from casmech.elements.force_types import entry_of
from casmech.elements.forces import contact
from casmech.equations.symbols import Coordinates
from casmech.model.ir import GROUND_INDEX, JointIR, PrimitiveIR, RowInfo
from casmech.model.lower import perpendicular_pair
from casmech.runtime import events

STILL = 1e-9  # slip speed (m/s) at or below which a point starting a run is tried stuck
UNLOADED = 1e-12  # N added to each point's normal force where a Group shares its holding force
TOUCH = 1e-12  # gap (m) at or below which a free point is touching at a segment's start
OPENING = 1e-6  # a stuck point's load, relative to its Group's mean, at which it has opened
SLIP_STOP = 1e-6  # slip speed (m/s) at or below which a sliding point that stopped is stuck
FREE, STUCK = "free", "stuck"
# the columns of one point in Contacts.state: gap, F_n, v_t (3), P (3), normal (3), gap rate
GAP, NORMAL_FORCE, SLIP, AT, NORMAL, CLOSING = 0, 1, slice(2, 5), slice(5, 8), slice(8, 11), 11
ROWS = 12


def elements(ir) -> list:
    """The contact elements with exact friction (`friction: {model: exact}`)."""
    return [f for f in ir.forces if getattr(entry_of(f.type), "points", None) is not None
            and isinstance(f.params.get("exact"), float) and f.params["exact"] == 1.0]


def label(mode) -> str:
    """A mode as the switch list writes it: free, stuck or sliding."""
    return mode if isinstance(mode, str) else "sliding"


class Contacts:
    """The contact points of a model's exact-friction contacts and their modes."""

    def __init__(self, ir):
        self.forces = elements(ir)
        x = Coordinates.create(ir.n_bodies)
        self.units: list[tuple[str, object, int]] = []  # (name, element, point index)
        values = []
        for force in self.forces:
            for k, point in enumerate(entry_of(force.type).points(force, x)):
                f_n, _, v_t = contact.tangential(force, x, point)
                self.units.append((f"{force.name}[{k}]", force, k))
                values.append(ca.vertcat(point.gap, f_n, v_t, point.at, point.normal,
                                         x.rate(point.gap)))
        self.names = [name for name, _, _ in self.units]
        self.x = x
        self.state = ca.Function("contact_points", [x.t, x.q, x.q_dot], [x.ground_fixed(
            ca.horzcat(*values) if values else ca.SX(ROWS, 0))])

    def points(self, t, q, q_dot) -> np.ndarray:
        """ROWS x points: each point's gap, F_n, v_t, P, normal, gap rate (the columns
        above)."""
        return np.array(self.state(t, q, q_dot)).reshape(ROWS, -1)

    def start(self, t, q, q_dot) -> dict:
        """The modes of a run's start: apart: free; touching and still: stuck; else sliding
        along the slip."""
        found = self.points(t, q, q_dot)
        return {name: self._touched(found[:, k]) if found[GAP, k] < 0 else FREE
                for k, name in enumerate(self.names)}

    @staticmethod
    def _touched(column) -> object:
        """The mode of a touching point: stuck when still, else sliding along its slip."""
        v_t = column[SLIP]
        speed = float(np.linalg.norm(v_t))
        return STUCK if speed <= STILL else tuple(float(v) for v in v_t / speed)

    def segment(self, ir, t, q, q_dot, modes: dict):
        """(the segment's model, {stuck point: its Group}): every element's params carry its
        points' modes; the stuck points of each body pair on one plane are held by one Group's
        rows."""
        found = self.points(t, q, q_dot)
        mine = {id(f) for f in self.forces}
        forces = tuple(replace(f, params=dict(f.params) | {"modes": tuple(
            modes[f"{f.name}[{k}]"] for k in range(self._count(f)))}) if id(f) in mine else f
            for f in ir.forces)
        groups: dict[tuple, list[int]] = {}
        for k, (name, force, _) in enumerate(self.units):
            if modes[name] == STUCK:
                key = (force.body_i, force.body_j, *np.round(found[NORMAL, k], 9))
                groups.setdefault(key, []).append(k)
        primitives, joints, held = list(ir.primitives), list(ir.joints), {}
        for members in groups.values():
            group, rows = self._group(q, found, members, len(primitives))
            joints.append(JointIR(group.names[0], "dp2", group.body_i, group.body_j,
                                  range(len(primitives), len(primitives) + len(rows)),
                                  rows[0].vectors["s_i"], self.units[members[0]][1].source))
            primitives += rows
            held |= dict.fromkeys(group.names, group)
        return replace(ir, forces=forces, primitives=tuple(primitives),
                       joints=tuple(joints)), held

    def _count(self, force) -> int:
        return sum(1 for _, f, _ in self.units if f is force)

    def _group(self, q, found, members: list[int], first: int):
        """(the Group of the stuck points `members` (columns of `found`), its rows numbered
        from `first`): two dp2 rows holding the points' centroid c along the plane, and with
        two points or more a dp1 row holding the turn about the normal."""
        force = self.units[members[0]][1]
        at = found[AT][:, members].T
        normal = np.asarray(found[NORMAL, members[0]], float)
        c = at.mean(axis=0)
        t1, t2 = perpendicular_pair(normal)  # (t1, t2, normal) right-handed
        i, j = force.body_i, force.body_j
        names = tuple(self.units[k][0] for k in members)
        info = RowInfo(names[0], "dp2", f"contact '{', '.join(names)}': stuck")
        rows = [PrimitiveIR("dp2", i, j, {"a_i": _local(q, i, a), "s_i": _local(q, i, c, True),
                                          "s_j": _local(q, j, c, True)}, None, row=info)
                for a in (t1, t2)]
        if len(members) > 1:
            rows.append(PrimitiveIR("dp1", i, j, {"a_i": _local(q, i, t1),
                                                  "a_j": _local(q, j, t2)}, None,
                                    row=replace(info, kind="dp1")))
        anchors = tuple(_local(q, j, p, True) for p in at)
        return Group(names, tuple(members), tuple(range(first, first + len(rows))), i, j,
                     anchors), rows

    def events(self, functions, modes: dict, held: dict) -> list:
        """A segment's stop events (module docstring), named `<point>.friction`."""
        x = Coordinates.create(functions.ir.n_bodies)
        lam = ca.SX.sym("lam", functions.n_rows)
        state = self.state(x.t, x.q, x.q_dot)
        forces = self.holding(functions, held, x, lam)
        found = []
        for k, (name, force, _) in enumerate(self.units):
            mode = modes[name]
            if mode == STUCK:  # slips, or its contact opens
                value = ca.fmax(ca.norm_2(forces[name]) - force.params["mu_s"] *
                                state[NORMAL_FORCE, k], state[GAP, k])
                direction = "rising"
            elif mode == FREE:
                value, direction = state[GAP, k], "falling"
            else:
                value, direction = ca.DM(mode).T @ state[SLIP, k], "falling"
            function = ca.Function("friction", [x.t, x.q, x.q_dot, x.q_ddot, lam],
                                   [x.ground_fixed(ca.SX(value))])
            found.append(events.Event(f"{name}.friction", function, direction, "stop"))
        return found

    def holding(self, functions, held: dict, x, lam) -> dict:
        """{stuck point: the friction force holding it (global, on body_j)} as expressions of
        the state and the multipliers. A Group's rows give a force F at the centroid and a
        torque about the normal; the points share them in proportion to their normal forces
        N_k (the shares of least sum |f_k|^2 / N_k): f_k = w_k (F + T_c (n x rho_k) /
        sum w_k |rho_k|^2), w_k = N_k / sum N, rho_k from the centre of pressure sum w_k P_k,
        T_c the torque about it. A Group can then hold exactly while |F| <= mu_s sum N
        (with no torque), as the rigid body it holds can; shares in equal parts would slip
        its least loaded point first, long before."""
        ir, out = functions.ir, {}
        state = self.state(x.t, x.q, x.q_dot)
        for group in {id(g): g for g in held.values()}.values():
            prims = [ir.primitives[r] for r in group.rows]
            frame_i, frame_j = x.frame(group.body_i), x.frame(group.body_j)
            tangents = [frame_i.A @ ca.DM(p.vectors["a_i"]) for p in prims[:2]]
            force = -sum(lam[r] * a for r, a in zip(group.rows[:2], tangents, strict=True))
            points = [frame_j.r + frame_j.A @ ca.DM(s) for s in group.anchors]
            centroid = sum(points) / len(points)
            normal = ca.cross(tangents[0], tangents[1])
            loads = [ca.fmax(state[NORMAL_FORCE, k], 0) + UNLOADED for k in group.members]
            weights = [n / sum(loads) for n in loads]
            pressure = sum(w * p for w, p in zip(weights, points, strict=True))
            rho = [p - pressure for p in points]
            turn = ca.cross(centroid - pressure, force).T @ normal
            if len(prims) > 2:  # the dp1 row's torque about the normal on body_j
                turn -= lam[group.rows[2]] * (tangents[0].T @ ca.cross(
                    normal, frame_j.A @ ca.DM(prims[2].vectors["a_j"])))
            spread = sum(w * (r.T @ r) for w, r in zip(weights, rho, strict=True))
            per = turn / ca.fmax(spread, 1e-300) if len(prims) > 2 else 0
            out |= {name: x.ground_fixed(w * (force + per * ca.cross(normal, r)))
                    for name, w, r in zip(group.names, weights, rho, strict=True)}
        return out

    def holds(self, functions, held: dict, result, k: int) -> dict:
        """{stuck point: its holding force (global)} in row k of a segment's Result."""
        if not held:
            return {}
        x = Coordinates.create(functions.ir.n_bodies)
        lam = ca.SX.sym("lam", functions.n_rows)
        forces = self.holding(functions, held, x, lam)
        function = ca.Function("holds", [x.t, x.q, x.q_dot, lam],
                               [ca.horzcat(*forces.values())])
        values = np.array(function(result.times[k], result.q[k], result.q_dot[k],
                                   result.lam[k])).reshape(3, -1)
        return dict(zip(forces, values.T, strict=True))

    def excess(self, functions, rows: dict, result) -> dict:
        """{stuck point: (|holding force| - mu_s F_n, mu_s F_n, the modes its Group slips in)}
        at a segment's first row."""
        found = self.points(result.times[0], result.q[0], result.q_dot[0])
        holds, out = self.holds(functions, rows, result, 0), {}
        for k, (name, force, _) in enumerate(self.units):
            if name in rows:
                hold = holds[name]
                limit = force.params["mu_s"] * max(float(found[NORMAL_FORCE, k]), 0.0)
                out[name] = (float(np.linalg.norm(hold)) - limit, limit,
                             self.release(rows[name], holds))
        return out

    def renewed(self, modes: dict, t, q, q_dot) -> dict:
        """At a segment's start (t, q, q_dot): the sliding points' slip directions as they
        are where they slip faster than SLIP_STOP (each point's event then watches its slip
        along its present direction), and the free points touching (gap <= TOUCH and
        closing: those touching with the one whose event fired) as touched."""
        found = self.points(t, q, q_dot)
        renewed = {n: tuple(float(v) for v in found[SLIP, k] / np.linalg.norm(found[SLIP, k]))
                   for k, n in enumerate(self.names) if isinstance(modes[n], tuple)
                   and np.linalg.norm(found[SLIP, k]) > SLIP_STOP}
        return renewed | {n: self._touched(found[:, k]) for k, n in enumerate(self.names)
                          if modes[n] == FREE and found[GAP, k] <= TOUCH
                          and found[CLOSING, k] < 0}

    @staticmethod
    def release(group, holds: dict) -> dict:
        """The modes of a Group's points when one of them slips: all slide (the rigid body
        they hold moves), each against its share of the holding force."""
        return {name: released(holds[name]) for name in group.names}

    def stopped(self, name: str, mode, functions, rows: dict, result) -> dict:
        """The modes after a point's event stopped a segment (in its last row): a stuck
        point whose contact opened is free, one that slips slides with its Group; a sliding
        point that stopped is tried stuck with every other touching point as still, one still
        slipping (or a free one that touched) slides on along its slip."""
        found = self.points(result.times[-1], result.q[-1], result.q_dot[-1])
        k = self.names.index(name)
        column = found[:, k]
        if mode == STUCK:
            holds = self.holds(functions, rows, result, -1)
            excess = np.linalg.norm(holds[name]) - self.units[k][1].params["mu_s"] * max(
                column[NORMAL_FORCE], 0.0)
            group = rows[name]
            loads = [max(found[NORMAL_FORCE, m], 0.0) for m in group.members]
            floor = OPENING * max(sum(loads) / len(loads), UNLOADED)
            if column[GAP] > excess or loads[group.names.index(name)] <= floor:
                # its contact opened (or carries no load), with any other of its Group's
                # unloaded with it: the others hold on
                return {n: FREE for n, load in zip(group.names, loads, strict=True)
                        if n == name or load <= floor}
            return self.release(rows[name], holds)
        if mode != FREE and np.linalg.norm(column[SLIP]) <= SLIP_STOP:
            # with every touching point as still (those of the same body stop together)
            return {n: STUCK for k, n in enumerate(self.names) if n == name or (
                found[GAP, k] < 0 and np.linalg.norm(found[SLIP, k]) <= SLIP_STOP)}
        return {name: self._touched(column)}

    def friction_force(self, functions, rows: dict, result, start: int) -> dict:
        """`<contact>.friction_force` of each exact element over a segment's rows from
        `start`: the magnitude of its points' summed friction, the holding forces included."""
        x = Coordinates.create(functions.ir.n_bodies)
        lam = ca.SX.sym("lam", functions.n_rows)
        holds, columns = self.holding(functions, rows, x, lam), {}
        for force in functions.ir.forces:
            if force.name not in {f.name for f in self.forces}:
                continue
            total = ca.SX.zeros(3, 1)
            for k, point in enumerate(entry_of(force.type).points(force, x)):
                name = f"{force.name}[{k}]"
                if name in rows:
                    total += holds[name]
                else:
                    f_n, _, v_t = contact.tangential(force, x, point)
                    total += contact.exact_friction(force, k, f_n, v_t)
            function = ca.Function("friction_force", [x.t, x.q, x.q_dot, lam],
                                   [x.ground_fixed(ca.norm_2(total))])
            count = len(result.times) - start  # one mapped call over the segment's rows
            columns[f"{force.name}.friction_force"] = np.array(function.map(count)(
                np.reshape(result.times[start:], (1, -1)), result.q[start:].T,
                result.q_dot[start:].T, result.lam[start:].T)).ravel() if count else np.zeros(0)
        return columns


@record
class Group:
    """The stuck points of one body pair on one plane and the rows holding them."""

    names: tuple[str, ...]
    members: tuple[int, ...]  # the points' columns in Contacts.state
    rows: tuple[int, ...]  # dp2 along t1, t2 at the centroid; dp1 (the turn) with 2 points+
    body_i: int
    body_j: int
    anchors: tuple[np.ndarray, ...]  # each point on body_j (its frame; ground: global)


def rows_of(held: dict) -> list[int]:
    """Every row of the Groups of a segment."""
    return sorted({row for group in held.values() for row in group.rows})


def _local(q, k: int, vector, point: bool = False) -> np.ndarray:
    """A global vector (a point when `point`) in body k's frame at q (ground: global)."""
    vector = np.asarray(vector, float)
    if k == GROUND_INDEX:
        return vector
    n = len(q) // 7
    r, p = q[3 * k:3 * k + 3], q[3 * n + 4 * k:3 * n + 4 * k + 4]
    a = np.array(ca.DM(euler.rotation(ca.DM(p))))
    return a.T @ (vector - r if point else vector)


def released(hold: np.ndarray) -> tuple:
    """The sliding mode of a point released against its holding force: it slips where the
    force was holding it from."""
    size = float(np.linalg.norm(hold))
    return tuple(float(v) for v in -hold / size) if size > 0 else FREE
