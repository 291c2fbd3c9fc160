"""The resolved model: what `schema` hands to `compiler`.

Everything here is checked and evaluated: parameters are numbers, vectors are numpy arrays in the
GLOBAL frame exactly as the file wrote them (at t = 0), orientations are unit Euler parameters,
functions of time are parsed expressions with the parameters bound. Names are still names
(`ground` included); turning them into indices is the compiler's job (model/lower.py).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import field
from typing import Any

import numpy as np

from casmech.core.expressions import Expr
from casmech.core.options import AnalysisOptions, DynamicsOptions
from casmech.core.records import record
from casmech.errors import Source

GROUND = "ground"
@record
class ScalarFunction:
    """A scalar expression of some named variables (t, length, ...) with parameters bound."""

    text: str
    expr: Expr
    constants: Mapping[str, float]
    variables: tuple[str, ...]
    source: Source | None = None

    def casadi(self, **variables: Any) -> Any:
        """Evaluate with CasADi operations (symbolic or numeric CasADi inputs)."""
        return self.expr.evaluate({**self.constants, **variables}, "casadi")

    def value(self, **variables: float) -> float:
        """Evaluate numerically."""
        return float(self.expr.evaluate({**self.constants, **variables}, "numpy"))

    @property
    def is_zero(self) -> bool:
        return self.expr.is_constant and self.value(**dict.fromkeys(self.variables, 0.0)) == 0.0


@record
class Body:
    """A resolved body: mass, inertia, initial pose and velocities in SI, its geometry and
    source."""

    name: str
    mass: float
    inertia: np.ndarray  # (3, 3) about the CM, body frame
    position: np.ndarray  # (3,) global CM at t = 0
    euler_parameters: np.ndarray  # (4,) unit, at t = 0
    velocity: np.ndarray  # (3,) global
    angular_velocity: np.ndarray  # (3,) GLOBAL frame
    geometry: tuple[Mapping[str, Any], ...] = ()
    source: Source | None = None


@record
class Joint:
    """One entry of `joints:`; composite and basic alike (a joint type is data, not a class).

    `vectors` holds the YAML vector keys that apply to the type, as numpy arrays:
    composite joints: at, axis (unit), axis_i, axis_j (unit), at_i, at_j: GLOBAL, t = 0;
    basic constraints: a_i, a_j, s_i, s_j (BODY frames), c (global).
    """

    name: str
    type: str
    body_i: str
    body_j: str
    vectors: Mapping[str, np.ndarray] = field(default_factory=dict)
    length: float | None = None  # distance joint (resolved default: |at_j - at_i| at t = 0)
    f: ScalarFunction | None = None  # basic constraints: f(t) (variables ("t",))
    # `driver:`: coordinate kind (casmech.elements.coordinate_kinds) -> f(t), variables ("t",)
    drivers: Mapping[str, ScalarFunction] = field(default_factory=dict)
    source: Source | None = None
    sources: Mapping[str, Source] = field(default_factory=dict)  # per-key locations
    # effort motors (schema/motors.py): effort mode -> f(t, coordinate, its rate) (torque ->
    # f(t, angle, angle_dot), force -> f(t, displacement, displacement_dot)); position and
    # speed motors are drivers above
    motor: Mapping[str, Any] = field(default_factory=dict)
    cut: bool = False  # joint formulation: a loop-closure constraint, never a tree joint
    reaction_frame: str = "global"  # `reactions: {frame: ...}` (runtime.reaction_frames)
    reaction_point: np.ndarray | None = None  # `reactions: {point: ...}`, global at t = 0
    # `limit:` (schema/contact.py): lower, upper (+-inf when absent), stiffness, damping
    limit: Mapping[str, float] | None = None
    # `friction:` (schema/contact.py): coulomb, viscous, static (default coulomb)
    friction: Mapping[str, float] | None = None
    # `initial:` (schema/initial.py): key -> number, or Euler parameters (orientation), or a
    # vector (angular_velocity); its keys' sources are in `sources` as "initial.<key>"
    initial: Mapping[str, Any] = field(default_factory=dict)
    # the type's scalar `options` beside `length` (a screw's lead)
    options: Mapping[str, Any] = field(default_factory=dict)
    # a coupling (joint_types.Couples): (joint, coordinate) of each coupled coordinate and its
    # coefficient; body_i and body_j are then the output joint's
    couples: tuple[tuple[str, str], ...] = ()
    coefficients: tuple[Any, ...] = ()


@record
class Force:
    """One entry of `forces:`. Points are GLOBAL at t = 0.

    tsda: body_i, body_j, at_i, at_j, stiffness, free_length, damping,
          actuator (variables ("t", "length", "length_dot"))
    rsda: joint, stiffness, free_angle, damping, actuator (variables ("t", "angle", "angle_dot"))
    force: body, at, value (3 ScalarFunctions of ("t",)), frame
    torque: body, value, frame
    bushing: body_i, body_j, vectors at, orientation (Euler parameters of the frame at t = 0),
             stiffness, damping, rotational_stiffness, rotational_damping, preload_force,
             preload_torque (3 each, components in the frame)
    sphere_plane, sphere_sphere, points_plane, capsule_plane: body_i, body_j, vectors (plane
             at, normal; center, center_i, center_j, points, ends), params
             (casmech/elements/forces/contact_spec.py)
    (each type's entry of casmech.elements.force_types resolves its fields: `resolve`)
    value and actuator may read the state (`pivot.angle`, `bar.vx`): casmech.core.states
    """

    name: str
    type: str
    body_i: str | None = None
    body_j: str | None = None
    body: str | None = None
    joint: str | None = None
    vectors: Mapping[str, np.ndarray] = field(default_factory=dict)
    stiffness: float = 0.0
    damping: float = 0.0
    free_length: float | None = None
    free_angle: float = 0.0
    actuator: ScalarFunction | None = None
    value: tuple[ScalarFunction, ScalarFunction, ScalarFunction] | None = None
    frame: str = "global"
    source: Source | None = None
    # contact (casmech/elements/forces/contact_spec.py): radii, the normal law and friction
    params: Mapping[str, float] = field(default_factory=dict)


@record
class Event:
    """One entry of `events:` (schema/events.py): `when` reads the names of
    schema.events.state_names besides t and parameters."""

    name: str
    when: ScalarFunction
    direction: str = "both"  # rising | falling | both
    action: str = "log"  # stop | log
    source: Source | None = None


@record
class Output:
    """One entry of `outputs:` (schema/outputs.py): `value` reads t, parameters, earlier
    outputs, the state and reactions (its `variables` name them)."""

    name: str
    value: ScalarFunction
    source: Source | None = None
    unit: str | None = None  # SI unit of its dimension ("m/s"), None when not stated


@record
class Analysis:
    """The `analysis:` block: what to run over which grid, and the options of its type (a
    core.options dataclass: formulation, ..., and the `solver:` block). `written`: the option
    keys the file wrote (dotted, with their values), from which a run of another type takes
    those its options have (casmech.analyze's analysis argument)."""

    type: str = "dynamics"
    t_end: float = 1.0
    output_step: float = 0.01
    rtol: float = 1e-8
    atol: float = 1e-10
    options: AnalysisOptions = field(default_factory=DynamicsOptions)
    source: Source | None = None
    events: tuple[Event, ...] = ()  # the model's `events:` (dynamics runs watch them)
    written: tuple[tuple[str, Any], ...] = ()
    sources: tuple[tuple[str, Source | None], ...] = ()  # where t_end, ..., method are


@record
class Estimation:
    """The `estimate:` block: parameters to fit (starting from their values), measurements."""

    parameters: tuple[str, ...]
    data: str  # path of the CSV, relative to the model file's folder
    outputs: tuple[str, ...] | None
    weights: Mapping[str, float]
    bounds: Mapping[str, tuple[float, float]]
    source: Source | None = None
    analysis: str = "dynamics"  # dynamics | kinematics (optimal/estimate_kinematics.py)


@record
class ControlInput:
    """An optimal-control input: the joint it drives, torque or force, and its bounds."""

    joint: str
    type: str  # torque | force
    lower: float
    upper: float


@record
class OptimalControl:
    """The `ocp:` block (columns are results-table column names)."""

    horizon: float
    intervals: int
    transcription: str
    controls: tuple[ControlInput, ...]
    effort: float
    terminal_cost: Mapping[str, tuple[float, float]]  # column -> (weight, target)
    terminal: Mapping[str, float]
    path: Mapping[str, tuple[float, float]]
    source: Source | None = None
    free_time: tuple[float, float] | None = None
    time_weight: float = 0.0
    initial_guess: str = "simulation"  # simulation | interpolation
    elements: int = 1  # collocation elements per control interval
    stabilized: bool = False  # collocation with position/velocity constraints at its points
    formulation: str = "auto"  # auto | joints | bodies
    degree: int = 3  # joints: collocation degree
    scheme: str = "radau"  # joints: radau | legendre
    piecewise: str = "constant"  # joints: controls constant | linear
    steps: int = 4  # joints: RK4 steps per shooting interval
    path_grid: str = "nodes"  # joints: nodes | fine
    weights: Mapping[str, float] = field(default_factory=dict)  # control name -> weight
    terminal_bounds: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    parameters: Mapping[str, tuple[float, float]] = field(default_factory=dict)  # decision
    initial_free: bool = False  # joints: the initial state is an unknown
    initial: Mapping[str, float] = field(default_factory=dict)  # column -> value at t0
    initial_bounds: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    # Lagrange terms: expression text -> (its function of t and the columns, weight)
    integral: Mapping[str, tuple[ScalarFunction, float]] = field(default_factory=dict)
    final: ScalarFunction | None = None  # Mayer term at the final time
    track: Mapping[str, tuple[ScalarFunction, float]] = field(default_factory=dict)  # table(t)
    solver: tuple[tuple[str, Any], ...] = ()  # IPOPT options written (core.ipopt_options)
    guess_file: tuple[str, str] | None = None  # a previous result's results.csv, controls.csv
    integrator: str = "rk4"  # joints, shooting: rk4 | cvodes | idas


@record
class ResolvedModel:
    """The validated, evaluated model that schema hands on (docs/architecture.md): every
    number in SI."""

    name: str
    description: str
    file: str
    text: str
    parameters: Mapping[str, float]
    gravity: np.ndarray
    bodies: tuple[Body, ...]
    joints: tuple[Joint, ...]
    forces: tuple[Force, ...]
    analysis: Analysis
    estimate: Estimation | None = None
    ocp: OptimalControl | None = None
    # component files the model was composed from (path -> text; docs/components.md): with
    # `text`, everything the model's content depends on
    files: Mapping[str, str] = field(default_factory=dict)
    # sha256 of the model file and of every file it read or named (components, tables, meshes,
    # estimation data): absolute path -> digest (schema/files.py), for metadata.json and replay
    sources: Mapping[str, str] = field(default_factory=dict)
    # the `--set` values it was loaded with (parameter -> text), so it can be loaded again
    overrides: Mapping[str, str] = field(default_factory=dict)
    # the parameters loaded as traced numbers (casmech.core.traced): name -> its CasADi
    # symbol; every number computed from them is a traced number (load_model_text's
    # `symbolic`)
    symbols: Mapping[str, Any] = field(default_factory=dict)
    outputs: tuple[Output, ...] = ()  # `outputs:` (results columns after the joint states)

    def __repr__(self) -> str:
        """One line: name, file, counts, parameters and analysis, not the whole model."""
        shown = ", ".join(f"{name}={value:.6g}" for name, value in
                          list(self.parameters.items())[:6])
        more = len(self.parameters) - 6
        shown += f", ... ({more} more)" if more > 0 else ""
        return (f"ResolvedModel('{self.name}' from {self.file}: {len(self.bodies)} bodies, "
                f"{len(self.joints)} joints, {len(self.forces)} forces; parameters: "
                f"{shown or 'none'}; analysis: {self.analysis.type}, t_end "
                f"{self.analysis.t_end:g} s)")
