"""The loops' ODE with its projection after every accepted step (formulations/loop_ode.py),
stepped by scipy's DOP853 here (the projection method of Hairer, Lubich and Roche: an explicit
Runge-Kutta method on the ODE, each step's end projected), on gallery loop models against
IDAS on the joint DAE at tight tolerance, with the constraint drift and a conservative
mechanism's energy (the r-p energy of the bundle: another formulation's)."""

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import DOP853

import casmech
from casmech.formulations import loop_ode
from casmech.formulations.joint_start import Loops, initial_state, quaternion_signs
from casmech.formulations.joint_system import build, saddle_terms
from casmech.formulations.tree import spanning_tree
from casmech.runtime import assembly
from casmech.runtime.joint_dynamics import _Integrator
from casmech.runtime.workspace import Workspace
from tests.conftest import MODELS


def _value(out) -> np.ndarray:
    return np.array(ca.DM(out).full()).ravel()


class Setup:
    def __init__(self, name: str):
        self.functions = casmech.compile(casmech.load(MODELS / f"{name}.yaml"))
        self.system = build(self.functions.ir, spanning_tree(self.functions.ir))
        q0, q_dot0 = assembly.initial_state(self.functions, 0.0)
        self.x0 = initial_state(self.system, q0, q_dot0)
        self.loops = Loops(self.system, 0.0, self.x0)
        self.z0 = self.loops.z(0.0, self.x0)
        self.signs = quaternion_signs(self.system, 0.0, self.x0, self.z0, q0,
                                      self.functions.n_bodies)
        self.loop = loop_ode.build(saddle_terms(self.functions.ir, self.system.tree),
                                   self.system.dynamics, self.system.layout.n_theta,
                                   self.loops.mask)

    def projected(self, rtol: float, t_end: float, project: bool = True):
        """(t, x) at every accepted step of DOP853 on the loops' ODE, each step's end
        projected (the derivative there evaluated again: the method's first stage)."""
        def ode(t, x):
            return _value(self.loop.ode(t, x))

        solver = DOP853(ode, 0.0, self.x0.copy(), t_end, rtol=rtol, atol=rtol / 100)
        steps = [(0.0, self.x0.copy())]
        while solver.status == "running":
            solver.step()
            if project:
                solver.y = _value(self.loop.project(solver.t, solver.y))
                solver.f = ode(solver.t, solver.y)
            steps.append((solver.t, solver.y.copy()))
        assert solver.status == "finished"
        return steps

    def idas(self, t_end: float, rtol: float = 1e-12) -> np.ndarray:
        states, _ = _Integrator(self.system, self.loops, rtol, rtol / 100, "bdf",
                                Workspace())(0.0, np.array([t_end]), self.x0, self.z0)
        return np.asarray(states)[:, -1]

    def residuals(self, t, x) -> np.ndarray:
        return _value(self.system.dynamics(t, x, np.zeros(2 * self.system.n_cut),
                                           self.loops.mask)[1])

    def energy(self, t, x) -> float:
        q, q_dot = (_value(v) for v in self.system.motion(t, x, self.z0, self.signs)[:2])
        kinetic, potential = self.functions["energy"](t, q, q_dot)
        return float(kinetic + potential)


@pytest.fixture(scope="module", params=["four_bar_released", "bricard"])
def setup(request):
    return Setup(request.param)


def test_projected_run_follows_the_dae(setup):
    reference = setup.idas(1.0)
    for rtol, tolerance in ((1e-6, 1e-5), (1e-9, 1e-8)):
        t, x = setup.projected(rtol, 1.0)[-1]
        assert t == 1.0
        # the global error of the run at this rtol over 1 s (coordinates ~1 rad): within
        # 10 rtol (measured 0.06-1.4 rtol); IDAS at 1e-12 is exact to these digits
        np.testing.assert_allclose(x, reference, rtol=0, atol=tolerance)


def test_projection_holds_the_rows_at_roundoff_where_the_plain_run_drifts(setup):
    drift = {project: max(np.abs(setup.residuals(t, x)).max()
                          for t, x in setup.projected(1e-5, 1.0, project))
             for project in (True, False)}
    # unit rows (per unit joint velocity): roundoff of coordinates ~1
    assert drift[True] < 1e-13
    assert drift[False] > 1e-9  # without it the rows drift by the integrator's error


def test_a_conservative_loop_keeps_its_energy(setup):
    """Gravity and joints only: the r-p energy at every projected step stays at its start's
    within the run's tolerance (the velocity projection only removes energy, by the square of
    the drift it corrects)."""
    steps = setup.projected(1e-8, 1.0)
    energies = np.array([setup.energy(t, x) for t, x in steps])
    scale = max(1.0, np.abs(setup.energy(0.0, setup.x0)))
    # rtol 1e-8 on states ~1: the energy's error ~1e-8 of its scale per step, a few steps
    # of it (measured spread 1.2e-9 and 6e-11 of the scale)
    np.testing.assert_allclose(energies, energies[0], rtol=0, atol=1e-7 * scale)
