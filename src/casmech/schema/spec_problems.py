"""Estimation, optimal control and parameter studies (schema/spec.py): the classes of the
`estimate:`, `ocp:` and `study:` sections, imported when a document first has one of them
(spec.ModelSpec, spec_base.Deferred)."""

# (annotations are objects here, not strings: no `from __future__ import annotations`, so that
# pydantic makes each class without evaluating them; docs/decisions/pydantic-defer-build.md)

from typing import Annotated, Any, Literal, Union

from pydantic import (
    Field,
    StrictBool,
    StrictFloat,
    StrictInt,
    StrictStr,
)

from casmech.core.spec_base import Name, Scalar, Spec

# ------------------------------------------------------- estimation and optimal control (issue 7)
Pair = Annotated[tuple[Scalar, ...], Field(min_length=2, max_length=2)]


class Estimate(Spec):
    """Fit parameters to measurements: `casmech optimize` (see casmech.optimal.estimate)."""

    parameters: Annotated[tuple[Name, ...], Field(min_length=1)]
    data: StrictStr  # CSV with a `t` column and measured results columns (path from the model)
    outputs: tuple[StrictStr, ...] | None = None  # default: every column of data but t
    weights: dict[StrictStr, Scalar] = Field(default_factory=dict)  # column -> weight (1)
    bounds: dict[StrictStr, Pair] = Field(default_factory=dict)  # parameter -> [low, high]
    # dynamics: simulated columns; kinematics: a fully driven mechanism's poses (no DOF)
    analysis: Literal["dynamics", "kinematics"] = "dynamics"


class Control(Spec):
    joint: Name
    type: Literal["torque", "force"] = "torque"
    bounds: Pair | None = None


class TerminalCost(Spec):
    weight: Scalar
    target: Scalar = 0


class Track(Spec):
    """A results column to follow: weight * integral (column - table(t))^2 dt."""

    table: StrictStr  # CSV with a `t` column, path relative to the model file's folder
    column: StrictStr | None = None  # the table's column (default: the tracked column's name)
    interpolation: Literal["linear", "cubic"] = "cubic"
    weight: Scalar = 1


class Objective(Spec):
    effort: Scalar = 1  # weight of the integral of u^T u
    time: Scalar = 0  # weight of the final time (with free_time)
    terminal: dict[StrictStr, TerminalCost] = Field(default_factory=dict)  # column -> cost
    weights: dict[StrictStr, Scalar] = Field(default_factory=dict)  # control -> effort weight
    # Lagrange terms: expression of the state -> weight; weight * integral expression^2 dt
    integral: dict[StrictStr, Scalar] = Field(default_factory=dict)
    final: StrictStr | None = None  # Mayer term: an expression at the final time, as written
    track: dict[StrictStr, Track] = Field(default_factory=dict)  # column -> table to follow


class GuessFile(Spec):
    """A previous `casmech optimize` result as the initial guess."""

    file: StrictStr  # its results.csv, relative to the model file's folder
    controls: StrictStr | None = None  # its controls.csv (default: beside `file`)


class OptimalControl(Spec):
    """An optimal control problem on the model: `casmech optimize` (casmech.optimal.ocp)."""

    horizon: Scalar
    intervals: StrictInt = 30
    transcription: Literal["collocation", "shooting"] = "collocation"
    controls: Annotated[tuple[Control, ...], Field(min_length=1)]
    objective: Objective = Field(default_factory=Objective)
    terminal: dict[StrictStr, Scalar] = Field(default_factory=dict)  # column -> value at the end
    path: dict[StrictStr, Pair] = Field(default_factory=dict)  # column -> [low, high] at nodes
    free_time: Pair | None = None  # [low, high] of a free final time; horizon is its guess
    # casmech.optimal.guess, or a previous result (casmech.optimal.warm_start)
    initial_guess: Literal["simulation", "interpolation"] | GuessFile = "simulation"
    elements: StrictInt = 1  # collocation elements per control interval
    stabilized: StrictBool = False  # collocation: Phi = 0 and Phi_q q_dot = nu at its points
    # joint coordinates (default where the joint formulation takes the mechanism) or bodies
    formulation: Literal["auto", "joints", "bodies"] = "auto"
    degree: StrictInt = Field(default=3, ge=1, le=9)  # joints: collocation polynomial degree
    scheme: Literal["radau", "legendre"] = "radau"  # joints: collocation points
    piecewise: Literal["constant", "linear"] = "constant"  # joints: the controls' shape
    steps: StrictInt = Field(default=4, ge=1, le=100)  # joints: RK4 steps per shooting interval
    path_grid: Literal["nodes", "fine"] = "nodes"  # joints: path bounds also inside intervals
    terminal_bounds: dict[StrictStr, Pair] = Field(default_factory=dict)  # column -> [lo, hi]
    parameters: dict[StrictStr, Pair] = Field(default_factory=dict)  # decision: [lo, hi]
    initial_free: StrictBool = False  # joints: the initial state is an unknown
    initial: dict[StrictStr, Scalar] = Field(default_factory=dict)  # column -> value at t0
    initial_bounds: dict[StrictStr, Pair] = Field(default_factory=dict)  # column -> [lo, hi]
    # IPOPT's options (casmech.core.ipopt_options, checked by schema.ocp_terms)
    solver: dict[StrictStr, Any] | None = None
    # joints, shooting: the intervals' integrator (RK4 steps, or SUNDIALS with sensitivities)
    integrator: Literal["rk4", "cvodes", "idas"] = "rk4"


# ---------------------------------------------------------- parameter studies (issue 18)
Number = Union[StrictInt, StrictFloat]  # noqa: UP007


class Study(Spec):
    """A parameter study: `casmech sweep` (casmech.study; docs/sweeps.md). Values are numbers
    or the command line's texts ("0.8:1.2:5", "100,200,400", "2,0.05"), checked by
    casmech.study.block with located errors."""

    grid: dict[StrictStr, StrictStr | Number | tuple[Number, ...]] = Field(default_factory=dict)
    samples: StrictInt = 0
    normal: dict[StrictStr, StrictStr | tuple[Number, ...]] = Field(default_factory=dict)
    uniform: dict[StrictStr, StrictStr | tuple[Number, ...]] = Field(default_factory=dict)
    seed: StrictInt = 0
    keep: tuple[StrictStr, ...] = ()
