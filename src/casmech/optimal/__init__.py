"""Exact sensitivities, parameter estimation and optimal control on a compiled model (issue 7).

    system.py       the system functions with a `theta` input (ParametricSystem): the model
                    loaded with those parameters traced, its data d(theta) by CasADi
    dae.py          the index-1 DAE, its differentiable consistent initial state, results columns
    sensitivity.py  IDAS simulation and forward/adjoint sensitivities of columns and integrals
    estimate.py     weighted least squares against measurements (IPOPT)
    controls.py     joint torques/forces as generalized forces
    ocp.py          optimal control: the problem, body-coordinate transcriptions (Opti + IPOPT)
                    and the choice of formulation
    joint_model.py  the model in joint coordinates, the controls as effort motors
    joint_ocp.py    optimal control in joint coordinates (nodes, closure, path, replay)
    collocation.py  direct collocation (Radau, Legendre; any degree)
    shooting.py     multiple shooting with RK4 steps
    control_shapes.py  piecewise-constant or piecewise-linear controls
"""
