"""runtime.dynamics keeps its IDAS integrators with the system (runtime.dae_integrators): the
number created is independent of the number of runs, and a kept one gives the results of a new
one (call counts and equalities, never timings)."""

import numpy as np
import pytest

import casmech
from casmech.runtime import dae_integrators
from tests.validation.runtime.test_dynamics import PENDULUM


def counted(monkeypatch) -> list:
    """Every casadi.integrator created from now on (its plugin name): the DAE runtime's and
    runtime.joint_dynamics' (both call the casadi module's)."""
    made, original = [], dae_integrators.ca.integrator

    def integrator(*args, **kwargs):
        made.append(args[1])
        return original(*args, **kwargs)

    monkeypatch.setattr(dae_integrators.ca, "integrator", integrator)
    return made


@pytest.mark.parametrize("formulation", ["rp", "romega"])
def test_repeated_runs_create_no_integrator(monkeypatch, formulation):
    functions = casmech.compile(casmech.loads(PENDULUM))
    made = counted(monkeypatch)
    first = casmech.analyze(functions, formulation=formulation, t_end=0.5)
    assert made == ["idas"]  # the index-2 DAE over the whole grid: one IDAS call
    again = [casmech.analyze(functions, formulation=formulation, t_end=0.5) for _ in range(3)]
    assert made == ["idas"]
    for result in again:  # the same integrator from the same inputs: the same numbers
        np.testing.assert_array_equal(result.q, first.q)
        np.testing.assert_array_equal(result.lam, first.lam)


def test_a_kept_integrator_gives_the_results_of_a_new_one():
    functions = casmech.compile(casmech.loads(PENDULUM))
    casmech.analyze(functions, formulation="rp", t_end=0.5)
    kept = casmech.analyze(functions, formulation="rp", t_end=0.5)
    fresh = casmech.analyze(casmech.compile(casmech.loads(PENDULUM)), formulation="rp",
                             t_end=0.5)
    np.testing.assert_array_equal(kept.q, fresh.q)  # deterministic: equal to the last bit
    np.testing.assert_array_equal(kept.q_ddot, fresh.q_ddot)


def test_another_grid_gets_its_own_integrator(monkeypatch):
    functions = casmech.compile(casmech.loads(PENDULUM))
    made = counted(monkeypatch)
    for t_end in (0.5, 0.3, 0.5, 0.3):
        casmech.analyze(functions, formulation="rp", t_end=t_end)
    assert made == ["idas", "idas"]  # one per output grid, each kept
