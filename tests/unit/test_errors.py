"""casmech.errors: failure messages name a body as a body and keep the solver's reason."""

import numpy as np

import casmech
from casmech.equations.checks import worst_joints
from casmech.errors import BodyName, FailureContext, Source, solver_reason
from casmech.runtime import assembly
from tests.conftest import MODELS

IDAS = ("Error in Function::call for 'dynamics' [IdasInterface] at .../function.cpp:1655:\n"
        ".../idas_interface.cpp:600: IDASolve returned \"IDA_TOO_MUCH_ACC\". Consult IDAS "
        "documentation.")


def test_bodies_are_named_as_bodies():
    context = FailureContext(0.5, "it failed", [(BodyName("rod"), Source("m.yaml", 4, 5), 1.0),
                                                ("pivot", Source("m.yaml", 9, 5), 0.5)])
    text = context.format()
    assert "m.yaml:4:5: body 'rod'" in text and "m.yaml:9:5: joint 'pivot'" in text


def test_worst_joints_marks_normalization_rows_as_bodies():
    """A residual only on the normalization rows (the Euler parameters of the file's pose
    doubled: p^T p - 1 = 3) blames the bodies, as bodies."""
    functions = casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"))
    q = assembly.initial_guess(functions)
    n = 3 * functions.n_bodies
    q[n:] *= 2.0
    phi = np.array(functions["phi"](0.0, q)).ravel()
    named = worst_joints(functions, phi, count=10)
    bodies = [name for name, _, value in named if isinstance(name, BodyName) and value > 1]
    assert sorted(bodies) == sorted(functions.body_names)


def test_solver_reason_keeps_what_sundials_said():
    assert solver_reason(RuntimeError(IDAS)) == ("IDAS: too much accuracy requested (rtol/atol "
                                                  "below what double precision reaches)")
    cvodes = IDAS.replace("IdasInterface", "CvodesInterface").replace('"IDA_TOO_MUCH_ACC"',
                                                                      '"CV_RHSFUNC_FAIL"')
    assert solver_reason(RuntimeError(cvodes)).startswith("CVODES: the right-hand side failed")
    assert solver_reason(RuntimeError("first\nlast line\n")) == "last line"
