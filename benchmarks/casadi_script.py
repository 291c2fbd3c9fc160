"""An independent CasADi r-p script: the baseline casmech's DAE is compared with per IDAS step.

The N-link spherical chain of systems.py (1 m, 1 kg bars, inertia [1e-4, m L^2/12, m L^2/12]
about the CM with x along the bar, spherical joints at the tips, gravity 9.81 in -z, released
horizontally from rest) in r-p coordinates with Euler parameters, written directly in CasADi SX
(no casmech), integrated by IDAS through one casadi.integrator call over the whole 0.01 s
output grid. Prints the wall time of that call, IDAS's counters and the error at t = 1 s
against reference.py (the planar RK4 reference, NumPy only).

    python benchmarks/casadi_script.py --n 8 --t-end 10 --rtol 1e-8
    python benchmarks/casadi_script.py --n 32 --form index1 --compile O3 --linsol csparse

Equations (Haug's r-p form; G(p) = [-e, -skew(e) + e0 I], omega_bar = 2 G p_dot):
    m r_ddot + Phi_r^T lam = m g
    4 G^T J G p_ddot + Phi_p^T lam = 8 G(p_dot)^T J G(p_dot) p
    Phi = [joint k: r_k + A_k s_minus - r_(k-1) - A_(k-1) s_plus;  p_k^T p_k - 1]
Forms: "ggl" (index 2, Gear-Gupta-Leimkuhler: x' = [q_dot + Phi_q^T mu, q_ddot], alg: the
equations of motion, Phi = 0, Phi_q q_dot = 0) and "index1" (alg: the equations of motion and
Phi_q q_ddot = gamma). Algebraic unknowns are out of IDAS's error test in both.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import tempfile
import time

import casadi as ca
import numpy as np
from systems import I_AXIAL, OUTPUT_STEP, T_CHECK, G, chain

from reference import Planar

L, MASS = 1.0, 1.0


def skew(v):
    return ca.vertcat(ca.horzcat(0, -v[2], v[1]), ca.horzcat(v[2], 0, -v[0]),
                      ca.horzcat(-v[1], v[0], 0))


def g_matrix(p):
    return ca.horzcat(-p[1:], -skew(p[1:]) + p[0] * ca.SX.eye(3))


def rotation(p):
    e0, e = p[0], p[1:]
    return (2 * e0**2 - 1) * ca.SX.eye(3) + 2 * (e @ e.T + e0 * skew(e))


def chain_equations(n: int):
    """(q, q_dot) SX symbols, mass matrix, forces, Phi: bodies ordered [r_1, p_1, r_2, p_2...]."""
    q, q_dot = ca.SX.sym("q", 7 * n), ca.SX.sym("q_dot", 7 * n)
    inertia = ca.diag(ca.DM([I_AXIAL, MASS * L**2 / 12, MASS * L**2 / 12]))
    s_minus, s_plus = ca.DM([-L / 2, 0, 0]), ca.DM([L / 2, 0, 0])
    blocks, forces, phi = [], [], []
    previous_tip = ca.DM.zeros(3)  # the ground joint at the origin
    for k in range(n):
        r, p, p_dot = q[7 * k:7 * k + 3], q[7 * k + 3:7 * k + 7], q_dot[7 * k + 3:7 * k + 7]
        g, g_dot = g_matrix(p), g_matrix(p_dot)
        blocks += [MASS * ca.SX.eye(3), 4 * g.T @ inertia @ g]
        forces += [ca.DM([0, 0, -MASS * G]), 8 * g_dot.T @ inertia @ g_dot @ p]
        phi += [r + rotation(p) @ s_minus - previous_tip, p.T @ p - 1]
        previous_tip = r + rotation(p) @ s_plus
    return q, q_dot, ca.diagcat(*blocks), ca.vertcat(*forces), ca.vertcat(*phi)


def dae_function(n: int, form: str) -> tuple[ca.Function, ca.Function]:
    """The DAE (x, z) -> (ode, alg), and (x) -> [M Phi_q^T; Phi_q 0], [F; gamma] for z0."""
    q, q_dot, mass, forces, phi = chain_equations(n)
    m = phi.numel()
    phi_q = ca.jacobian(phi, q)
    gamma = -ca.jtimes(phi_q @ q_dot, q, q_dot)
    q_ddot, lam = ca.SX.sym("q_ddot", 7 * n), ca.SX.sym("lam", m)
    motion = mass @ q_ddot + phi_q.T @ lam - forces
    x = ca.vertcat(q, q_dot)
    if form == "ggl":
        mu = ca.SX.sym("mu", m)
        z = ca.vertcat(q_ddot, lam, mu)
        ode = ca.vertcat(q_dot + phi_q.T @ mu, q_ddot)
        alg = ca.vertcat(motion, phi, phi_q @ q_dot)
    else:
        z = ca.vertcat(q_ddot, lam)
        ode, alg = ca.vertcat(q_dot, q_ddot), ca.vertcat(motion, phi_q @ q_ddot - gamma)
    kkt = ca.Function("kkt", [x], [ca.blockcat([[mass, phi_q.T], [phi_q, ca.SX(m, m)]]),
                                   ca.vertcat(forces, gamma)])
    return ca.Function("dae", [x, z], [ode, alg], ["x", "z"], ["ode", "alg"]), kkt


def compiled(function: ca.Function, flags: str) -> ca.Function:
    """The Function and its Jacobian (jac_<name>, which casadi.external looks up for IDAS)
    generated as C, built by gcc with `flags`, loaded."""
    directory = tempfile.mkdtemp(prefix="casadi_script_")
    generator = ca.CodeGenerator("dae.c")
    generator.add(function)
    generator.add(function.jacobian())
    generator.generate(directory + os.sep)
    library = os.path.join(directory, "dae.so")
    subprocess.run(["gcc", "-shared", "-fPIC", flags, "-o", library,
                    os.path.join(directory, "dae.c")], check=True)
    return ca.external(function.name(), library)


def initial_state(n: int, kkt: ca.Function, n_z: int):
    """x0 (bars along +x at rest) and z0 = [q_ddot, lam, (mu = 0)] from the KKT system."""
    q0 = np.concatenate([[k + 0.5, 0, 0, 1, 0, 0, 0] for k in range(n)])
    x0 = np.concatenate([q0, np.zeros(7 * n)])
    lhs, rhs = (np.array(value) for value in kkt(x0))
    z0 = np.zeros(n_z)
    z0[:len(rhs)] = np.linalg.solve(lhs, rhs.ravel())
    return x0, z0


class Runner:
    """The script as a benchmark tool (run.py's `casadi-script`: GGL, SX, default linear
    solver), chains only: build once, then one IDAS call per run over the 0.01 s grid."""

    tool = "casadi-script"

    def __init__(self, system):
        if not system.name.startswith("chain"):
            raise ValueError("the CasADi script models the N-link chain only")
        start = time.perf_counter()
        self.n = len(system.bars)
        self.function, kkt = dae_function(self.n, "ggl")
        self.x0, self.z0 = initial_state(self.n, kkt, self.function.size1_in(1))
        self.build_time = {"compile": time.perf_counter() - start}
        self.system = system

    def run(self, setting: dict, t_end: float) -> dict:
        x, z = ca.SX.sym("x", len(self.x0)), ca.SX.sym("z", len(self.z0))
        ode, alg = self.function(x, z)
        times = OUTPUT_STEP * np.arange(1, int(round(t_end / OUTPUT_STEP)) + 1)
        x_dot = np.array(ca.Function("f", [x, z], [ode])(self.x0, self.z0)).ravel()
        options = {"reltol": setting["rtol"], "abstol": setting["atol"],
                   "max_num_steps": 100000, "suppress_algebraic": True, "calc_ic": False,
                   "step0": 1e-6, "init_xdot": list(x_dot)}
        start, cpu_start = time.perf_counter(), time.process_time()
        integrator = ca.integrator("chain", "idas", {"x": x, "z": z, "ode": ode, "alg": alg},
                                   0.0, list(times), options)
        xf = np.array(integrator(x0=self.x0, z0=self.z0)["xf"])
        wall = time.perf_counter() - start
        cpu = time.process_time() - cpu_start
        q = xf[:7 * self.n, int(round(T_CHECK / OUTPUT_STEP)) - 1]
        return {"wall": wall, "cpu": cpu, "points": chain_points(q, self.n),
                "extra": {"steps": int(integrator.stats()["nsteps"])}}


def chain_points(q: np.ndarray, n: int) -> np.ndarray:
    """The CM and tip of every bar from the r-p coordinates, in systems.points' order."""
    points = []
    for k in range(n):
        r, p = q[7 * k:7 * k + 3], q[7 * k + 3:7 * k + 7]
        tip = r + np.array(ca.evalf(rotation(ca.DM(p)) @ ca.DM([L / 2, 0, 0]))).ravel()
        points += [r, tip]
    return np.array(points)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=8)
    parser.add_argument("--t-end", type=float, default=1.0)
    parser.add_argument("--rtol", type=float, default=1e-8)
    parser.add_argument("--atol", type=float, help="default rtol / 100")
    parser.add_argument("--form", choices=("ggl", "index1"), default="ggl")
    parser.add_argument("--compile", metavar="LEVEL", help="generate C, build with gcc -LEVEL "
                        "(O3, O2, O0)")
    parser.add_argument("--linsol", default="qr", help="IDAS linear solver plugin")
    parser.add_argument("--step0", type=float, default=1e-6)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    atol = args.atol if args.atol is not None else args.rtol / 100

    start = time.perf_counter()
    function, kkt = dae_function(args.n, args.form)
    x0, z0 = initial_state(args.n, kkt, function.size1_in(1))
    if args.compile:
        function = compiled(function, "-" + args.compile)
    sym = ca.MX if args.compile else ca.SX  # SX: IDAS's residual and Jacobian are SX too
    x, z = sym.sym("x", len(x0)), sym.sym("z", len(z0))
    ode, alg = function(x, z)
    times = OUTPUT_STEP * np.arange(1, int(round(args.t_end / OUTPUT_STEP)) + 1)
    options = {"reltol": args.rtol, "abstol": atol, "max_num_steps": 100000,
               "suppress_algebraic": True, "calc_ic": False, "step0": args.step0,
               "init_xdot": list(np.array(ca.Function("f", [x, z], [ode])(x0, z0)).ravel()),
               "linear_solver": args.linsol, "record_time": True}
    integrator = ca.integrator("chain", "idas", {"x": x, "z": z, "ode": ode, "alg": alg},
                               0.0, list(times), options)
    build = time.perf_counter() - start

    walls = []
    for _ in range(args.repeats):
        start = time.perf_counter()
        out = integrator(x0=x0, z0=z0)
        walls.append(time.perf_counter() - start)
    stats = integrator.stats()
    xf = np.array(out["xf"])
    check = int(round(T_CHECK / OUTPUT_STEP)) - 1
    points = chain_points(xf[:7 * args.n, check], args.n)
    reference = Planar(chain(args.n)).solve()["points"]
    error = float(np.max(np.linalg.norm(points - reference, axis=1)))
    wall = float(np.median(walls))
    steps = stats["nsteps"]
    print(f"chain{args.n} {args.form} {'C -' + args.compile if args.compile else 'SX'} "
          f"linsol {args.linsol}, rtol {args.rtol:g} atol {atol:g}, t_end {args.t_end:g}: "
          f"wall {wall:.3f} s (median of {args.repeats}; build {build:.2f} s), "
          f"error at t = 1 s {error:.2e} m")
    print(f"  nsteps {steps}, nfevals {stats['nfevals']}, nlinsetups {stats['nlinsetups']}, "
          f"nniters {stats['nniters']}, netfails {stats['netfails']}, "
          f"nncfails {stats['nncfails']}")
    print(f"  per step: {1e6 * wall / steps:.1f} us wall, {1e6 * stats['t_wall_total'] / steps:.1f}"
          f" us in IDAS, residual {1e6 * stats['t_wall_daeF'] / steps:.1f} us, Jacobian "
          f"{1e6 * stats['t_wall_jacF'] / steps:.1f} us ({stats['n_call_jacF']} calls)")


if __name__ == "__main__":
    main()
