"""The Formulation protocol: what every formulation of forward dynamics gives the runtime, and
the registry FORMULATIONS of them (the `formulation:` option's values, with "auto").

A formulation is one small frozen class (docs/architecture.md, "Adding a formulation"):

- `name`, and `takes_couplings` (whether rows over several joints' coordinates, gears and
  couplers, fit its states);
- `states(functions, stabilization)`: the names of the states it integrates, differential
  and algebraic;
- `system(functions, stabilization)`: a System, its equations as CasADi Functions: `residual`
  (t, x, z, p) -> (ode, alg), an ODE x' = ode for CVODES when z is empty, else a semi-explicit
  DAE x' = ode, 0 = alg for IDAS; `rows` (t, x, z, p) -> (q, q_dot, q_ddot, lam), its state
  as the results row reads it (body coordinates: r-p positions, their rates, every row's
  multiplier); and where p carries the start time (`time_offset`: the residual's t is then
  relative to it);
- `start(functions, system, t0, q, q_dot)`: a Start, the consistent (x, z, p) at the
  assembled body coordinates (q, q_dot);
- `integrator_options(...)`: what SUNDIALS needs at a start besides the tolerances (an
  index-2 DAE's first step and algebraic tolerances; none by default).
- `equations(ir, data)`: its own equations for a lowered model, numeric or over the model
  data's symbols, where it has such an object (joint: the JointSystem its `system` wraps):
  what the consumers that build on a formulation's own terms take (the FMU, the Python
  controller, the parametric library); None by default;
- `controlled(ir, data)`: its equations for optimal control (ControlEquations: the ODE with
  the efforts as an input, the rows its state must satisfy, the conversions to and from
  body coordinates), over the model data's symbols; the joint formulation offers them,
  another raises a UsageError saying so (optimal control takes FORMULATIONS["joint"]'s);
- `residual(functions, stabilization)` and `library_stabilizations()`: the residual a compiled
  C library generates for it (backends: formulations.residuals.oracles and
  backends.parametric.bundle loop over the registry), for which stabilizations (none by
  default).

runtime.analyses runs a registered formulation by name: the built-in classes through the
runtime's own drivers for them (runtime.formulation_run), any other through the generic one,
which integrates `system` from `start` over the one driver (runtime.driver). The built-in ones
(formulations.builtin: rp, romega, joint) implement all of the protocol, so the generic driver
runs them too. The registry is formulations.registry.FORMULATIONS.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import casadi as ca
import numpy as np

from casmech.core.options import DynamicsSolver
from casmech.core.records import record
from casmech.equations.functions import SystemFunctions
from casmech.errors import UsageError
from casmech.model.ir import ModelIR

DEFAULT = DynamicsSolver()  # the defaults (core.options)


@record
class States:
    """The names of a formulation's states: x (differential) and z (algebraic)."""

    differential: tuple[str, ...]
    algebraic: tuple[str, ...] = ()


@record(eq=False)
class System:
    """A formulation's equations for one model (module docstring). `time_offset`: the index
    of p that holds the start time, the residual's and rows' t being relative to it (None:
    t is absolute)."""

    residual: ca.Function
    rows: ca.Function
    time_offset: int | None = None

    @property
    def n_z(self) -> int:
        return self.residual.size1_in(2)

    @property
    def integrator(self) -> str:
        """The SUNDIALS integrator it takes: IDAS for a DAE, CVODES for an ODE."""
        return "idas" if self.n_z else "cvodes"


@record
class Start:
    """A consistent start: states x, algebraic states z and parameters p."""

    x: np.ndarray
    z: np.ndarray
    p: np.ndarray


class ControlEquations(ABC):
    """A formulation's equations for optimal control over one model (Formulation.controlled),
    in its state x = [coordinates; velocities] (the first n_coordinates entries, then the
    rest). Every method takes the model data `d` (model.parametric.split's vector: numeric,
    or an expression of the controls and design parameters) and returns CasADi expressions,
    except the numeric start terms (`state`, `independent`, `signs`). A formulation with
    loop closures keeps n_cut rows: the multipliers z = [lam; mu] of its DAE, `closure`'s
    rows, and `mask` (1 for a row left out, 0 for one kept)."""

    @property
    @abstractmethod
    def n_x(self) -> int:
        """The size of x."""

    @property
    @abstractmethod
    def n_coordinates(self) -> int:
        """How many of x's entries are coordinates (the velocities follow)."""

    @property
    @abstractmethod
    def n_cut(self) -> int:
        """How many loop-closure rows (0: x' is an ODE of x alone)."""

    @abstractmethod
    def ode(self, t, x, d, z=None, mask=None):
        """x' under the model's own forces (its motors included); with loops, the DAE's x'
        at multipliers z with the rows of `mask` left out."""

    @abstractmethod
    def forced(self, t, x, tau, d):
        """x' with the efforts tau (generalized forces along x's velocities, in their order)
        added to the model's own forces: the ODE optimal control's controls drive."""

    @abstractmethod
    def closure(self, t, x, d) -> tuple:
        """(the loop-closure rows at position level, at velocity level), each n_cut rows."""

    @abstractmethod
    def multipliers(self, t, x, d, kept) -> ca.SX:
        """z = [lam; mu = 0] making the kept rows' (indices) accelerations vanish."""

    @abstractmethod
    def invariants(self, x) -> ca.SX:
        """Rows of x alone that every state satisfies (unit quaternions: |p|^2 - 1)."""

    @abstractmethod
    def periodic(self) -> list[int]:
        """The indices into x of the coordinates that are angles (2 pi leaves the pose)."""

    @abstractmethod
    def state(self, q, q_dot, d) -> np.ndarray:
        """x at the body coordinates (q, q_dot) (r-p positions and their rates)."""

    @abstractmethod
    def independent(self, t, x, d) -> np.ndarray:
        """1 for each loop-closure row independent of the rows before it at (t, x), else 0."""

    @abstractmethod
    def signs(self, t, x, q, d) -> np.ndarray:
        """+1 or -1 per body: the Euler parameters of `body` that continue those of q."""

    @abstractmethod
    def body(self, t, x, z, signs, d) -> tuple:
        """(q, q_dot, q_ddot, lam) at (t, x, z): the body coordinates, their rates and
        accelerations (Euler parameters times `signs`) and every constraint row's
        multiplier, which the results columns and the costs read."""


@record
class Formulation(ABC):
    """The protocol (module docstring): a frozen dataclass per formulation implements states,
    system and start."""

    name: str
    takes_couplings: bool = True

    @abstractmethod
    def states(self, functions: SystemFunctions, stabilization: str = "ggl") -> States:
        """The names of the states it integrates (with the analysis's stabilization)."""

    @abstractmethod
    def system(self, functions: SystemFunctions, stabilization: str = "ggl") -> System:
        """Its equations for the model of `functions`; `stabilization`: the analysis's
        (core.options), which a formulation without constraint rows in its state ignores."""

    def equations(self, ir: ModelIR, data: ca.SX | None = None):
        """Its own equations for the lowered model `ir`, the object its `system` is built
        from, over a numeric IR or a symbolic one (`data`: model.parametric.split's symbols,
        every function's trailing input "d"): what a consumer that needs more of a
        formulation than System takes (the FMU's C functions, the Python controller's bound
        functions, a parametric library's joint functions: docs/architecture.md "Adding a
        formulation"). None by default: the formulation's equations are its System alone."""
        return None

    def controlled(self, ir: ModelIR, data: ca.SX) -> ControlEquations | None:
        """Its equations for optimal control over the parametric IR `ir` written in the model
        data's symbols `data` (model.parametric.split), or None for a model it does not take
        (joint: loops through a floating body). Not offered by default: a UsageError naming
        the formulation."""
        raise UsageError(f"the {self.name} formulation does not offer the equations optimal "
                         "control takes (Formulation.controlled: the ODE with the efforts as "
                         "an input, its closure rows, body coordinates); optimal control "
                         "takes the joint formulation's (formulations.registry.FORMULATIONS"
                         "['joint']), or body coordinates with formulation: bodies")

    def residual(self, functions: SystemFunctions, stabilization: str = "ggl") -> ca.Function:
        """Its system's residual alone, (t, x, z, p) -> (ode, alg): what a compiled C library
        generates for it (`library_stabilizations`); by default system(...).residual. Over
        a parametric library's bundle (its functions take the model data d last:
        model.parametric.data_size) it takes d as the last entries of p
        (model.parametric.with_data calls the functions with them)."""
        return self.system(functions, stabilization).residual

    def library_stabilizations(self) -> tuple[str, ...]:
        """The stabilizations whose `residual` a compiled C library generates for it, with
        its Jacobian blocks for IDAS, under the residual's own name, where its `system` finds
        it in a compiled bundle; none by default (the library then holds the model's
        functions only, over which `system` builds its equations when a run loads it)."""
        return ()

    @abstractmethod
    def start(self, functions: SystemFunctions, system: System, t0: float, q: np.ndarray,
              q_dot: np.ndarray) -> Start:
        """The consistent start at t0 from the assembled r-p state (q, q_dot)."""

    def integrator_options(self, functions: SystemFunctions, system: System, t: float,
                           x: np.ndarray, z: np.ndarray, p: np.ndarray, rtol: float,
                           atol: float, interval: float,
                           settings: DynamicsSolver = DEFAULT) -> dict:
        """SUNDIALS options a start (t, x, z, p) of the system needs besides the tolerances
        (an index-2 DAE: its first step, sized by the output `interval`, and the absolute
        tolerances of its algebraic states); none by default."""
        return {}


def indexed(prefix: str, count: int) -> tuple[str, ...]:
    """prefix[0], prefix[1], ...: state names of a vector."""
    return tuple(f"{prefix}[{k}]" for k in range(count))
