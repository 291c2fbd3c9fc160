"""Six robots of example-robot-data simulated 1 s to 1e-7 m by casmech, MuJoCo and Pinocchio
in one run (issue 36's robots).

    python benchmarks/robots.py                        # the six variants, 3 repeats, ~15 min
    python benchmarks/robots.py --robots ur5 solo12 --repeats 5 --builds 1

The variants: UR5, Panda with free fingers (its URDF without <mimic>: two independent finger
slides) and with locked fingers (the finger joints made fixed), Kinova j2s6s200, the Talos
left arm, Solo12 (fixed base). Each engine reads the same URDF copy:

- casmech: `casmech.importers.urdf.import_urdf` (posed at the initial state) written to YAML
  without the stops it makes of the URDF limits (below); timed: `casmech.load` +
  `casmech.compile(model, "auto")` (with an empty cache interpreted, as the API's default
  `casmech.compile(model)` is: what a first run gets; the library it would build behind for
  the next call is left out here, and that next call is the compiled one below) +
  `casmech.analyze(..., "dynamics", t_end=1, rtol=r, atol=r/100)`,
  then the same analyze again on the same functions (the integrator built); the same with
  `compile(model, "compiled")` from a warm cache; the cold build (`compile(model,
  "compiled")` into an empty CASMECH_CACHE_DIR and the first analyze, which builds the tree's
  ODE library: wall time, and the CPU time of the process and its compiler children); and the
  default call on the import with its stops, against its own rtol 1e-12 run. The joints'
  Coulomb friction casmech imports from URDF `friction` (the Talos arm) is left out of both.
- MuJoCo: `MjModel.from_xml_path` of the URDF copy without visual and collision elements
  (fixed links fused as casmech merges them); contacts, joint limits and joint friction (URDF
  `friction`, which MuJoCo reads as frictionloss) off; the URDF damping kept; RK4 at the largest
  step of 1/n s (n about 1.25x apart) that reaches 1e-7 m.
- Pinocchio: `pin.aba` with tau = -D v (the URDF damping, which casmech imports as damping
  elements) in `scipy.integrate.solve_ivp`, the fastest of DOP853, RK45 and LSODA at the
  loosest tolerance (half decades, atol = rtol / 100) that reaches 1e-7 m.

Why no stops: an unactuated arm under gravity reaches a URDF limit within half a second from
the states tried, and there the engines' laws differ (casmech's penalty stop, MuJoCo's soft
constraint, none in `pin.aba`), so their trajectories cannot agree to 1e-7 m; without stops
all three integrate the same smooth ODE. The initial state: joint angles and slides drawn
uniformly (`--seed`) in the middle 40% of the URDF limits (an angle without limits, or with
limits wider than 2 pi, in the middle 40% of (-pi, pi)), velocities uniform in +-0.5 rad/s
(m/s for slides), zero torques, gravity -9.81 z. The error of a run is the largest distance at
t = 1 s between a body's centre of mass and the reference's, over the bodies; the reference is
Pinocchio's ABA in DOP853 at rtol = atol = 1e-13, checked against casmech compiled at rtol
1e-12. casmech's rtol is the loosest half decade reaching 1e-7 m compiled, and for the
default call on an empty cache (interpreted: method auto may take another method there) the
loosest reaching it interpreted. Every time is CPU
time (the machine is shared), the median of `--repeats` runs, the engines interleaved within
each repeat. Needs `pin`, `mujoco` and `example-robot-data` (pip install ".[bench]").
"""

from __future__ import annotations

import argparse
import contextlib
import datetime
import os
import platform
import resource
import shutil
import statistics
import subprocess
import tempfile
import time
import xml.etree.ElementTree as ET
from importlib import metadata
from pathlib import Path

import numpy as np

URDFS = {
    "ur5": "ur_description/urdf/ur5_robot.urdf",
    "panda": "panda_description/urdf/panda.urdf",
    "panda_locked": "panda_description/urdf/panda.urdf",
    "kinova": "kinova_description/robots/kinova.urdf",
    "talos_arm": "talos_data/robots/talos_left_arm.urdf",
    "solo12": "solo_description/robots/solo12.urdf",
}
LABELS = {"ur5": "UR5", "panda": "Panda, free fingers", "panda_locked": "Panda, locked fingers",
          "kinova": "Kinova j2s6s200", "talos_arm": "Talos left arm", "solo12": "Solo12"}
LEVEL = 1e-7  # m: the accuracy every engine's setting reaches at t = 1 s
T_END = 1.0
HOT_CALLS = 8  # compiled analyze calls after the second, their median "hot" (casmech_call)
HALF_DECADES = tuple(float(f"{m}e{e}") for e in range(-4, -12, -1) for m in (3, 1))
CASMECH_RTOLS = HALF_DECADES  # 3e-4, 1e-4, 3e-5, ... 1e-11; atol = rtol / 100
PIN_RTOLS = HALF_DECADES
PIN_METHODS = ("DOP853", "RK45", "LSODA")
MUJOCO_STEPS = tuple(m * 10**e for e in range(1, 5) for m in (5, 6.25, 8, 10, 12.5, 16, 20,
                                                                25, 32, 40) if m * 10**e >= 50)
MUJOCO_STEPS = tuple(sorted({int(n) for n in MUJOCO_STEPS}))  # steps per second, ~1.25x apart


def robots_folder() -> Path:
    distribution = metadata.distribution("example-robot-data")
    return Path(distribution.locate_file("cmeel.prefix/share/example-robot-data"))


def variant_urdf(name: str, folder: Path) -> tuple[Path, Path]:
    """(the variant's URDF copy in `folder`, the same without visual and collision elements for
    MuJoCo, which cannot resolve package:// mesh names)."""
    tree = ET.parse(robots_folder() / "robots" / URDFS[name])
    root = tree.getroot()
    if name.startswith("panda"):
        for joint in root.findall("joint"):
            mimic = joint.find("mimic")
            if mimic is not None:
                joint.remove(mimic)
            if name == "panda_locked" and "finger" in joint.get("name"):
                joint.set("type", "fixed")
    path = folder / f"{name}.urdf"
    tree.write(path)
    for link in root.iter("link"):
        for element in link.findall("visual") + link.findall("collision"):
            link.remove(element)
    bare = folder / f"{name}_mujoco.urdf"
    tree.write(bare)
    return path, bare


class Robot:
    """One variant in the three engines, at one initial state."""

    def __init__(self, name: str, folder: Path):
        import pinocchio as pin

        self.name, self.folder = name, folder
        self.urdf, self.bare = variant_urdf(name, folder)
        self.pin = pin.buildModelFromUrdf(str(self.urdf))
        self.data = self.pin.createData()
        self.joints = [self.pin.names[k] for k in range(1, self.pin.njoints)]
        assert all(j.nv == 1 for j in list(self.pin.joints)[1:]), name
        self.damping = np.asarray(self.pin.damping, float)
        children = {j.get("name"): j.find("child").get("link")
                    for j in ET.parse(self.urdf).getroot().findall("joint")}
        self.links = [children[j] for j in self.joints]  # a joint's moving body
        self.stops = self._stops()

    def _stops(self) -> dict[str, tuple[float, float]]:
        """{joint: (lower, upper)} of the stops casmech's import makes of the URDF limits."""
        from casmech.importers.urdf import import_urdf

        imported = import_urdf(self.urdf, output=self.folder / f"{self.name}.yaml",
                               mesh_dirs=(robots_folder().parent,))
        self.imported_joints = [j.data["name"] for j in imported.joints]
        return {j.data["name"]: (j.data["limit"]["lower"], j.data["limit"]["upper"])
                for j in imported.joints if "limit" in j.data}

    # -- the state ---------------------------------------------------------------------
    def draw_state(self, rng) -> tuple[np.ndarray, np.ndarray]:
        q, v = [], []
        for k, joint in enumerate(list(self.pin.joints)[1:]):
            low = self.pin.lowerPositionLimit[joint.idx_q]
            high = self.pin.upperPositionLimit[joint.idx_q]
            if joint.nq == 2 or not (np.isfinite(low) and np.isfinite(high)) or (
                    high - low > 2 * np.pi and "Revolute" in joint.shortname()):
                low, high = -np.pi, np.pi
            if self.joints[k] in self.stops:
                low, high = (max(low, self.stops[self.joints[k]][0]),
                             min(high, self.stops[self.joints[k]][1]))
            q.append(low + (high - low) * rng.uniform(0.3, 0.7))
            v.append(rng.uniform(-0.5, 0.5))
        return np.array(q), np.array(v)

    def first_stop(self, times: np.ndarray, trajectory: np.ndarray) -> float | None:
        """The first of `times` at which a joint of `trajectory` (rows of angles) is beyond
        one of casmech's stops (None: never)."""
        beyond = np.zeros(len(times), bool)
        for k, joint in enumerate(self.joints):
            if joint in self.stops:
                low, high = self.stops[joint]
                beyond |= (trajectory[:, k] < low) | (trajectory[:, k] > high)
        return float(times[np.argmax(beyond)]) if beyond.any() else None

    # -- Pinocchio ---------------------------------------------------------------------
    def pin_q(self, angles: np.ndarray) -> np.ndarray:
        q = []
        for k, joint in enumerate(list(self.pin.joints)[1:]):
            q.extend([np.cos(angles[k]), np.sin(angles[k])] if joint.nq == 2 else [angles[k]])
        return np.array(q)

    def pin_rhs(self):
        import pinocchio as pin

        model, data, n, damping = self.pin, self.data, self.pin.nv, self.damping
        if all(j.nq == 1 for j in list(model.joints)[1:]):
            def rhs(t, y):
                v = y[n:]
                return np.concatenate([v, pin.aba(model, data, y[:n], v, -damping * v)])
        else:
            def rhs(t, y):
                v = y[n:]
                return np.concatenate([v, pin.aba(model, data, self.pin_q(y[:n]), v,
                                                  -damping * v)])
        return rhs

    def pin_run(self, q0, v0, method: str, rtol: float, atol: float, dense: bool = False):
        from scipy.integrate import solve_ivp

        return solve_ivp(self.pin_rhs(), (0.0, T_END), np.concatenate([q0, v0]),
                         method=method, rtol=rtol, atol=atol, dense_output=dense)

    def centres_pin(self, angles: np.ndarray) -> dict[str, np.ndarray]:
        import pinocchio as pin

        pin.forwardKinematics(self.pin, self.data, self.pin_q(angles))
        return {link: self.data.oMi[k + 1].act(self.pin.inertias[k + 1].lever)
                for k, link in enumerate(self.links) if self.pin.inertias[k + 1].mass > 0}

    # -- casmech -----------------------------------------------------------------------
    def write_casmech(self, q0, v0, stops: bool) -> Path:
        """The import posed at (q0, v0) as YAML without the joints' Coulomb friction; without
        `stops`, the joints' `limit:` stops left out too."""
        from casmech.importers.emit import to_yaml
        from casmech.importers.urdf import import_urdf

        out = self.folder / f"{self.name}{'_stops' if stops else ''}.yaml"
        imported = import_urdf(self.urdf, dict(zip(self.joints, q0, strict=True)),
                               dict(zip(self.joints, v0, strict=True)), output=out,
                               mesh_dirs=(robots_folder().parent,))
        for joint in imported.joints:
            # the URDF's dry friction (Talos arm), as in MuJoCo's model and pin.aba: none
            joint.data.pop("friction", None)
            if not stops:
                joint.data.pop("limit", None)
        out.write_text(to_yaml(imported))
        return out

    @staticmethod
    def centres_casmech(result) -> dict[str, np.ndarray]:
        frame = result.to_dataframe()
        last = frame.iloc[-1]
        assert abs(frame.index[-1] - T_END) < 1e-12
        bodies = {c[:-2] for c in frame.columns if c.endswith(".x")}
        return {b: np.array([last[f"{b}.{c}"] for c in "xyz"]) for b in bodies}

    # -- MuJoCo ------------------------------------------------------------------------
    def mujoco_model(self, steps: int):
        import mujoco

        model = mujoco.MjModel.from_xml_path(str(self.bare))
        model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
        model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
        model.opt.timestep = T_END / steps
        model.opt.gravity[:] = (0, 0, -9.81)
        model.dof_frictionloss[:] = 0.0
        model.jnt_limited[:] = 0  # as casmech's model without its stops
        return model

    def mujoco_start(self, model, data, q0, v0) -> None:
        import mujoco

        mujoco.mj_resetData(model, data)
        for k, joint in enumerate(self.joints):
            data.qpos[model.joint(joint).qposadr[0]] = q0[k]
            data.qvel[model.joint(joint).dofadr[0]] = v0[k]

    def mujoco_check(self, model) -> None:
        """MuJoCo's model holds the URDF's masses and damping (its fused bodies as casmech's)."""
        for k, joint in enumerate(self.joints):
            j = model.joint(joint)
            assert abs(model.dof_damping[j.dofadr[0]] - self.damping[k]) < 1e-12, joint
            mass = self.pin.inertias[k + 1].mass
            assert abs(model.body(self.links[k]).mass[0] - mass) < 1e-9 * (1 + mass), joint


def error(centres: dict[str, np.ndarray], reference: dict[str, np.ndarray]) -> float:
    """The largest distance of a body's centre of mass from the reference's [m] over the
    reference's bodies (each engine names a body after its URDF link)."""
    missing = set(reference) - set(centres)
    assert not missing, f"bodies missing: {sorted(missing)}"
    return max(float(np.linalg.norm(centres[b] - reference[b])) for b in reference)


@contextlib.contextmanager
def cache_dir(path: Path):
    """CASMECH_CACHE_DIR = path for the block. The default call's background build stays off
    (CASMECH_BACKGROUND_BUILD=0, set by main): the empty cache must stay empty, and a build
    behind would share the cores with the engines timed next; benchmarks/first_runs.py measures
    the first and next runs with it."""
    old = os.environ.get("CASMECH_CACHE_DIR")
    os.environ["CASMECH_CACHE_DIR"] = str(path)
    try:
        yield path
    finally:
        if old is None:
            os.environ.pop("CASMECH_CACHE_DIR", None)
        else:
            os.environ["CASMECH_CACHE_DIR"] = old


def cpu() -> float:
    """CPU time of this process and its finished children (the compiler) [s]."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


# -- the timed calls ------------------------------------------------------------------------

def casmech_call(yaml: Path, rtol: float, mode: str, cache: Path) -> tuple[dict, object]:
    """load + compile(model, mode) + analyze, then the same analyze again on the same
    functions: (CPU times, the first result). The first analyze of a bundle builds its
    integrator; the second is what each further run of the same functions costs; compiled,
    "hot" is the median of HOT_CALLS more (a session's steady state: Python's specializing
    interpreter has warmed the Python around the C, which runs ~2x slower in the second)."""
    import casmech

    with cache_dir(cache):
        start = time.process_time()
        model = casmech.load(yaml)
        loaded = time.process_time()
        functions = casmech.compile(model, mode)
        compiled = time.process_time()
        result = casmech.analyze(functions, "dynamics", t_end=T_END, rtol=rtol, atol=rtol / 100)
        end = time.process_time()
        casmech.analyze(functions, "dynamics", t_end=T_END, rtol=rtol, atol=rtol / 100)
        again = time.process_time()
        hot = []
        for _ in range(HOT_CALLS if mode == "compiled" else 0):
            begin = time.process_time()
            casmech.analyze(functions, "dynamics", t_end=T_END, rtol=rtol, atol=rtol / 100)
            hot.append(time.process_time() - begin)
    times = {"load": loaded - start, "compile": compiled - loaded, "first": end - compiled,
             "total": end - start, "again": again - end}
    return times | ({"hot": statistics.median(hot)} if hot else {}), result


def casmech_cold_build(yaml: Path, rtol: float) -> dict:
    """compile(model, "compiled") into an empty cache, then the first analyze, which builds
    the tree's ODE library (runtime.joint_dynamics.compiled_system): wall times, and CPU times
    with the compilers'."""
    import casmech

    model = casmech.load(yaml)
    with tempfile.TemporaryDirectory(prefix="robots-cold-") as tmp, cache_dir(Path(tmp)):
        wall, start = time.perf_counter(), cpu()
        functions = casmech.compile(model, "compiled")
        wall_bundle, cpu_bundle = time.perf_counter() - wall, cpu() - start
        casmech.analyze(functions, "dynamics", t_end=T_END, rtol=rtol, atol=rtol / 100)
        return {"wall": time.perf_counter() - wall, "cpu": cpu() - start,
                "wall_bundle": wall_bundle, "cpu_bundle": cpu_bundle}


def mujoco_run(robot: Robot, model, data, q0, v0, steps: int) -> tuple[float, dict]:
    import mujoco

    start = time.process_time()
    robot.mujoco_start(model, data, q0, v0)
    mujoco.mj_step(model, data, nstep=steps)
    elapsed = time.process_time() - start
    mujoco.mj_forward(model, data)
    return elapsed, {robot.links[k]: data.body(robot.links[k]).xipos.copy()
                     for k in range(len(robot.joints))
                     if model.body(robot.links[k]).mass[0] > 0}


def pin_run(robot: Robot, q0, v0, method: str, rtol: float) -> tuple[float, dict]:
    start = time.process_time()
    solution = robot.pin_run(q0, v0, method, rtol, rtol / 100)
    elapsed = time.process_time() - start
    assert solution.success, solution.message
    return elapsed, robot.centres_pin(solution.y[:robot.pin.nv, -1])


# -- one robot ------------------------------------------------------------------------------


def loosest_casmech(yaml, mode: str, cache, target, log, label: str, against: str = ""):
    """(rtol, error) of the loosest of CASMECH_RTOLS whose run of `yaml` ends within LEVEL of
    the centres `target`, or None."""
    for rtol in CASMECH_RTOLS:
        _, result = casmech_call(yaml, rtol, mode, cache)
        e = error(Robot.centres_casmech(result), target)
        log(f"  {label} rtol {rtol:g}: {e:.2e} m{against}")
        if e <= LEVEL:
            return rtol, e
    return None


def prepare(name: str, folder: Path, seed: int, log) -> dict:
    """The robot at its initial state, the reference, each engine's setting reaching LEVEL."""
    robot = Robot(name, folder)
    q0, v0 = robot.draw_state(np.random.default_rng(seed))
    solution = robot.pin_run(q0, v0, "DOP853", 1e-10, 1e-12, dense=True)
    times = np.linspace(0, T_END, 2001)
    first_stop = robot.first_stop(times, solution.sol(times)[:robot.pin.nv].T)
    log(f"{name}: seed {seed}: q0 {np.round(q0, 4).tolist()}, v0 {np.round(v0, 4).tolist()}; "
        f"a stop reached at t = {first_stop} s")
    reference_run = robot.pin_run(q0, v0, "DOP853", 1e-13, 1e-13)
    reference = robot.centres_pin(reference_run.y[:robot.pin.nv, -1])
    yaml = robot.write_casmech(q0, v0, stops=False)
    out = {"robot": robot, "q0": q0, "v0": v0, "reference": reference, "yaml": yaml,
           "first_stop": first_stop}
    # casmech: the loosest rtol reaching LEVEL, judged on the compiled run (the interpreted
    # run evaluates the same functions: its error is checked in the timed runs)
    warm = folder / "cache"
    casmech_call(yaml, 1e-4, "compiled", warm)  # builds the library into the warm cache
    _, tight = casmech_call(yaml, 1e-12, "compiled", warm)
    out["casmech_vs_reference"] = error(Robot.centres_casmech(tight), reference)
    log(f"{name}: casmech compiled at rtol 1e-12 is {out['casmech_vs_reference']:.2e} m from "
        "the reference")
    found = loosest_casmech(yaml, "compiled", warm, reference, log, "casmech")
    if found is None:
        raise RuntimeError(f"{name}: casmech reaches {LEVEL} m at no rtol of {CASMECH_RTOLS}")
    out["casmech_rtol"], out["casmech_error"] = found
    # the default call on an empty cache runs interpreted, where method auto takes another
    # method than compiled (docs/decisions/method-auto.md): its own loosest rtol
    found = loosest_casmech(yaml, "interpreted", warm, reference, log, "casmech interpreted")
    if found is None:
        raise RuntimeError(f"{name}: casmech interpreted reaches {LEVEL} m at no rtol of "
                           f"{CASMECH_RTOLS}")
    out["auto_rtol"] = found[0]
    if robot.stops:  # the import as it is, with its stops: against its own tight run
        out["yaml_stops"] = robot.write_casmech(q0, v0, stops=True)
        _, tight = casmech_call(out["yaml_stops"], 1e-12, "interpreted", warm)
        own = Robot.centres_casmech(tight)
        found = loosest_casmech(out["yaml_stops"], "interpreted", warm, own, log,
                                "casmech with stops", " from its rtol 1e-12 run")
        if found is not None:
            out["stops_rtol"], out["stops_own"] = found[0], own
    # MuJoCo: the largest step reaching LEVEL (the larger ones that diverge print MuJoCo's
    # instability warning)
    import mujoco

    robot.mujoco_check(robot.mujoco_model(1000))
    for steps in MUJOCO_STEPS:
        model = robot.mujoco_model(steps)
        data = mujoco.MjData(model)
        _, centres = mujoco_run(robot, model, data, q0, v0, steps)
        e = error(centres, reference)
        log(f"  MuJoCo RK4 dt 1/{steps}: {e:.2e} m")
        if e <= LEVEL:
            out["mujoco_steps"], out["mujoco_error"] = steps, e
            break
    else:
        raise RuntimeError(f"{name}: MuJoCo reaches {LEVEL} m at no step")
    # Pinocchio: each method's loosest rtol reaching LEVEL; the fastest is kept at timing
    out["pin"] = {}
    for method in PIN_METHODS:
        for rtol in PIN_RTOLS:
            elapsed, centres = pin_run(robot, q0, v0, method, rtol)
            e = error(centres, reference)
            if e <= LEVEL:
                out["pin"][method] = (rtol, e)
                log(f"  Pinocchio {method} rtol {rtol:g}: {e:.2e} m, {1e3 * elapsed:.1f} ms")
                break
    return out


def measure(prepared: dict, repeats: int, builds: int, log) -> dict:
    import mujoco

    robot, q0, v0 = prepared["robot"], prepared["q0"], prepared["v0"]
    yaml, reference = prepared["yaml"], prepared["reference"]
    warm = robot.folder / "cache"
    empty = Path(tempfile.mkdtemp(prefix="robots-empty-"))
    steps = prepared["mujoco_steps"]
    samples = {k: [] for k in ("auto_total", "auto_setup", "auto_first", "auto_again",
                               "compiled_total", "compiled_first", "compiled_again",
                               "compiled_hot",
                               "mujoco_load", "mujoco", "build_wall", "build_cpu",
                               "build_wall_bundle", "build_cpu_bundle",
                               "stops_total", "stops_again",
                               *(f"pin_{m}" for m in prepared["pin"]))}
    errors = {}
    rtol = prepared["casmech_rtol"]
    for k in range(repeats):  # the engines interleaved
        times, result = casmech_call(yaml, prepared["auto_rtol"], "auto", empty)
        assert not any(empty.iterdir()), "mode auto wrote to the cache"
        assert result.metadata["mode"] == "interpreted", result.metadata
        samples["auto_total"].append(times["total"])
        samples["auto_setup"].append(times["load"] + times["compile"])
        samples["auto_first"].append(times["first"])
        samples["auto_again"].append(times["again"])
        errors["auto"] = error(Robot.centres_casmech(result), reference)
        times, result = casmech_call(yaml, rtol, "compiled", warm)
        assert result.metadata["mode"] == "compiled", result.metadata
        samples["compiled_total"].append(times["total"])
        samples["compiled_first"].append(times["first"])
        samples["compiled_again"].append(times["again"])
        samples["compiled_hot"].append(times["hot"])
        errors["compiled"] = error(Robot.centres_casmech(result), reference)
        if "stops_rtol" in prepared:
            times, result = casmech_call(prepared["yaml_stops"], prepared["stops_rtol"], "auto",
                                         empty)
            samples["stops_total"].append(times["total"])
            samples["stops_again"].append(times["again"])
            errors["stops"] = error(Robot.centres_casmech(result), prepared["stops_own"])
        start = time.process_time()
        model = robot.mujoco_model(steps)
        data = mujoco.MjData(model)
        samples["mujoco_load"].append(time.process_time() - start)
        elapsed, centres = mujoco_run(robot, model, data, q0, v0, steps)
        samples["mujoco"].append(elapsed)
        errors["mujoco"] = error(centres, reference)
        for method, (pin_rtol, _) in prepared["pin"].items():
            elapsed, centres = pin_run(robot, q0, v0, method, pin_rtol)
            samples[f"pin_{method}"].append(elapsed)
            errors[f"pin_{method}"] = error(centres, reference)
        if k < builds:
            build = casmech_cold_build(yaml, rtol)
            for key, value in build.items():
                samples[f"build_{key}"].append(value)
    shutil.rmtree(empty, ignore_errors=True)
    median = {k: statistics.median(s) for k, s in samples.items() if s}
    best = min(prepared["pin"], key=lambda m: median[f"pin_{m}"])
    median["pin"] = median[f"pin_{best}"]
    row = {"robot": robot.name, "nv": robot.pin.nv, "rtol": rtol,
           "auto_rtol": prepared["auto_rtol"], "median": median,
           "errors": errors, "mujoco_steps": steps, "pin_method": best,
           "pin_rtol": prepared["pin"][best][0], "stops": len(robot.stops),
           "damped": int(np.count_nonzero(robot.damping)),
           "casmech_vs_reference": prepared["casmech_vs_reference"],
           "first_stop": prepared["first_stop"], "stops_rtol": prepared.get("stops_rtol")}
    log(f"{robot.name}: " + ", ".join(f"{k} {1e3 * v:.1f} ms" for k, v in median.items()))
    return row


# -- where a cold build goes -----------------------------------------------------------------

STAGES = (  # (module, function): each call timed in a cold build, nested calls included
    ("casmech.backends.codegen", "bundle"),  # the bundle's CasADi graphs (mapped kernels)
    ("casmech.backends.codegen", "dae_oracles"),  # the DAE residuals and their Jacobians
    ("casmech.backends.generate", "write_sources"),  # C of the bundle
    ("casmech.backends.generate", "write_dae_sources"),  # C of the DAE residuals
    ("casmech.backends.generate", "write_unit_sets"),  # C of the bundle and the joint ODE's
    ("casmech.backends.joint_library", "motion"),  # the results rows (in halves when large)
    ("casmech.backends.codegen", "build_libraries"),  # gcc of the bundle and DAE residuals
    ("casmech.backends.library", "build_libraries"),  # gcc of a functions library
    ("casmech.backends.manifest", "write"),  # the manifest (cache write)
    ("casmech.backends.trust", "private"),  # the cache directory's permissions
    ("casmech.backends.trust", "verify"),  # hashes of the libraries when loaded
    ("casmech.runtime.joint_dynamics", "build"),  # the joint system's CasADi graph
    ("casmech.backends.library", "content_key"),  # the functions' serialization (cache key)
)


def build_stages(yaml: Path, rtol: float) -> tuple[dict, list]:
    """One cold build (casmech_cold_build) with every STAGES function wrapped by a wall-clock
    timer, and every compiler command timed: ({stage: (calls, s)}, [(command's source, s,
    bytes of C)]); the stages overlap where one calls another."""
    import importlib

    from casmech.backends import build as build_module

    timings: dict[str, list] = {}
    commands: list = []
    originals = []
    for module_name, name in STAGES:
        module = importlib.import_module(module_name)
        original = getattr(module, name)
        originals.append((module, name, original))
        key = f"{module_name.rsplit('.', 1)[1]}.{name}"

        def timed(*args, _original=original, _key=key, **kwargs):
            start = time.perf_counter()
            try:
                return _original(*args, **kwargs)
            finally:
                entry = timings.setdefault(_key, [0, 0.0])
                entry[0] += 1
                entry[1] += time.perf_counter() - start

        setattr(module, name, timed)
    run = build_module._run

    def timed_run(command, cwd):
        start = time.perf_counter()
        try:
            return run(command, cwd)
        finally:
            source = next((c for c in command if c.endswith(".c")), None)
            size = (Path(cwd) / source).stat().st_size if source else 0
            commands.append((source or "link " + command[-2], time.perf_counter() - start,
                             size))

    build_module._run = timed_run
    try:
        totals = casmech_cold_build(yaml, rtol)
    finally:
        build_module._run = run
        for module, name, original in originals:
            setattr(module, name, original)
    timings.update({k: (1, v) for k, v in totals.items()})
    return timings, commands


def stages_report(name: str, yaml: Path, rtol: float) -> str:
    timings, commands = build_stages(yaml, rtol)
    lines = [f"### {LABELS[name]}", "", "| stage | calls | wall s |", "|---|---|---|"]
    lines += [f"| {k} | {calls} | {seconds:.2f} |" for k, (calls, seconds) in timings.items()]
    lines += ["", "| compiler command (source) | wall s | C bytes |", "|---|---|---|"]
    lines += [f"| {source} | {seconds:.2f} | {size} |" for source, seconds, size in commands]
    return "\n".join(lines)


# -- a cold build at two commits -----------------------------------------------------------

def cold_build_worker(yaml: Path, rtol: float, runs: int) -> dict:
    """In a fresh process (the `src/` on PYTHONPATH): casmech_cold_build, then the compiled
    run's analyze on the built functions `runs` times (CPU s, median)."""
    import casmech

    build = casmech_cold_build(yaml, rtol)
    with tempfile.TemporaryDirectory(prefix="robots-run-") as tmp, cache_dir(Path(tmp)):
        functions = casmech.compile(casmech.load(yaml), "compiled")
        casmech.analyze(functions, "dynamics", t_end=T_END, rtol=rtol, atol=rtol / 100)
        times = []
        for _ in range(runs):
            start = time.process_time()
            casmech.analyze(functions, "dynamics", t_end=T_END, rtol=rtol, atol=rtol / 100)
            times.append(time.process_time() - start)
    return {**build, "run": statistics.median(times)}


def compare_builds(names: list[str], commit: str, repeats: int, seed: int, log) -> str:
    """Cold build and compiled run of each robot by `src/` at `commit` and by this checkout's,
    alternating, each in a fresh process (cold_build_worker); medians."""
    import json
    import sys

    here = Path(__file__).resolve().parent
    lines = ["| robot | src | cold build s wall (CPU) | compile() s wall (CPU) | compiled "
             "run ms (median of 5) |", "|---|---|---|---|---|"]
    with tempfile.TemporaryDirectory(prefix="robots-ab-") as tmp:
        archive = subprocess.run(["git", "archive", commit, "src"], cwd=here.parent,
                                 capture_output=True, check=True).stdout
        subprocess.run(["tar", "-x", "-C", tmp], input=archive, check=True)
        sources = {commit: Path(tmp) / "src", "this": here.parent / "src"}
        for name in names:
            folder = Path(tmp) / name
            folder.mkdir()
            robot = Robot(name, folder)
            q0, v0 = robot.draw_state(np.random.default_rng(seed))
            yaml = robot.write_casmech(q0, v0, stops=False)
            samples = {label: [] for label in sources}
            for _ in range(repeats):
                for label, src in sources.items():
                    env = {**os.environ, "PYTHONPATH": str(src)}
                    done = subprocess.run(
                        [sys.executable, str(here / "robots.py"), "--cold-build-worker",
                         str(yaml)], env=env, capture_output=True, text=True, check=True)
                    samples[label].append(json.loads(done.stdout.splitlines()[-1]))
                    log(f"{name} {label}: {samples[label][-1]}")
            for label, runs in samples.items():
                m = {k: statistics.median(r[k] for r in runs) for k in runs[0]}
                lines.append(f"| {LABELS[name]} | {label} | {m['wall']:.1f} ({m['cpu']:.1f}) | "
                             f"{m['wall_bundle']:.1f} ({m['cpu_bundle']:.1f}) | "
                             f"{1e3 * m['run']:.2f} |")
    return "\n".join(lines)


# -- output -----------------------------------------------------------------------------------

def header() -> str:
    import casadi
    import mujoco
    import pinocchio

    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True, cwd=Path(__file__).parent).stdout.strip()
    dirty = subprocess.run(["git", "status", "--porcelain", "--", "../src"],
                           capture_output=True, text=True,
                           cwd=Path(__file__).parent).stdout.strip()
    cpu_name = next((line.split(":", 1)[1].strip() for line in
                     Path("/proc/cpuinfo").read_text().splitlines()
                     if line.startswith("model name")), platform.processor())
    return (f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, "
            f"{os.cpu_count()} cores of {cpu_name}, Python {platform.python_version()}, "
            f"casmech {commit}{' (src/ modified)' if dirty else ''}, CasADi "
            f"{casadi.__version__}, MuJoCo {mujoco.__version__}, Pinocchio "
            f"{pinocchio.__version__}, example-robot-data "
            f"{metadata.version('example-robot-data')}, load {os.getloadavg()[0]:.1f}")


def table(rows: list[dict]) -> str:
    ms = 1e3
    lines = [
        "| robot | nv | stops / dampers | casmech rtol | default call (auto) ms: whole "
        "(load + compile, first analyze) | again ms | compiled ms: whole (first analyze) | "
        "again ms | hot ms | MuJoCo RK4 dt | MuJoCo ms (load ms) | Pinocchio | Pinocchio ms | "
        "cold build s wall (CPU): compile() + first analyze; compile() alone |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        m = r["median"]
        build = (f"{m['build_wall']:.1f} ({m['build_cpu']:.1f}); compile() "
                 f"{m['build_wall_bundle']:.1f} ({m['build_cpu_bundle']:.1f})"
                 if "build_wall" in m else "not run")
        lines.append(
            f"| {LABELS[r['robot']]} | {r['nv']} | {r['stops']} / {r['damped']} | "
            f"{r['rtol']:g} (default {r['auto_rtol']:g}) | {ms * m['auto_total']:.1f} "
            f"({ms * m['auto_setup']:.1f}, "
            f"{ms * m['auto_first']:.1f}) | {ms * m['auto_again']:.1f} | "
            f"{ms * m['compiled_total']:.1f} ({ms * m['compiled_first']:.1f}) | "
            f"{ms * m['compiled_again']:.2f} | {ms * m['compiled_hot']:.2f} | "
            f"1/{r['mujoco_steps']} | {ms * m['mujoco']:.2f} "
            f"({ms * m['mujoco_load']:.1f}) | {r['pin_method']} {r['pin_rtol']:g} | "
            f"{ms * m['pin']:.2f} | {build} |")
    lines += ["", "Ratios to issue 36's targets (casmech / peer; targets: default call <= 0.5x "
              "MuJoCo and <= 1x Pinocchio, cold build <= 5 s):", "",
              "| robot | default whole / MuJoCo | default again / MuJoCo | default again / "
              "Pinocchio | compiled again / MuJoCo | compiled again / Pinocchio | "
              "compiled hot / MuJoCo | cold build / 5 s |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        m = r["median"]
        build = f"{m['build_wall'] / 5:.1f}" if "build_wall" in m else "not run"
        lines.append(
            f"| {LABELS[r['robot']]} | {m['auto_total'] / m['mujoco']:.0f} | "
            f"{m['auto_again'] / m['mujoco']:.1f} | {m['auto_again'] / m['pin']:.2f} | "
            f"{m['compiled_again'] / m['mujoco']:.2f} | {m['compiled_again'] / m['pin']:.2f} "
            f"| {m['compiled_hot'] / m['mujoco']:.2f} | {build} |")
    lines += ["", "Errors at t = 1 s against the reference [m] (each timed setting), the "
              "reference against casmech compiled at rtol 1e-12, when the reference first "
              "passes a stop of casmech's import, and the default call on the import with its "
              "stops (its error against its own rtol 1e-12 run):", "",
              "| robot | casmech default | casmech compiled | MuJoCo | Pinocchio | "
              "reference check | first stop passed at | with stops: rtol, whole ms, again ms, "
              "error |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        e, m = r["errors"], r["median"]
        stop = "no stops" if r["first_stop"] is None else f"{r['first_stop']:.2f} s"
        stops = ("none" if r["stops_rtol"] is None else
                 f"{r['stops_rtol']:g}, {ms * m['stops_total']:.0f}, "
                 f"{ms * m['stops_again']:.0f}, {e['stops']:.1e}")
        lines.append(f"| {LABELS[r['robot']]} | {e['auto']:.1e} | {e['compiled']:.1e} | "
                     f"{e['mujoco']:.1e} | {e['pin_' + r['pin_method']]:.1e} | "
                     f"{r['casmech_vs_reference']:.1e} | {stop} | {stops} |")
    return "\n".join(lines)


def main() -> None:
    os.environ["CASMECH_BACKGROUND_BUILD"] = "0"  # cache_dir's docstring
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--robots", nargs="+", default=list(URDFS), choices=list(URDFS))
    parser.add_argument("--repeats", type=int, default=3, help="timed runs of each engine")
    parser.add_argument("--builds", type=int, default=3, help="cold builds per robot (at "
                        "most --repeats; 0: none)")
    parser.add_argument("--seed", type=int, default=36)
    parser.add_argument("--stages", action="store_true", help="instead: one cold build of "
                        "each robot with its stages timed (where the build goes)")
    parser.add_argument("--compare-builds", metavar="COMMIT", help="instead: the cold build "
                        "and compiled run of each robot by src/ at COMMIT and by this checkout, "
                        "alternating, --repeats times each")
    parser.add_argument("--cold-build-worker", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.cold_build_worker:
        import json

        os.environ["CASMECH_ALLOWED_DIRS"] = str(robots_folder())
        print(json.dumps(cold_build_worker(args.cold_build_worker, 1e-7, 5)))
        return
    started = header()

    def log(text: str) -> None:
        print(f"# {text}", flush=True)

    if args.compare_builds:
        os.environ["CASMECH_ALLOWED_DIRS"] = str(robots_folder())
        table_text = compare_builds(args.robots, args.compare_builds, args.repeats, args.seed,
                                    log)
        print(f"\nStarted {started}; load at the end {os.getloadavg()[0]:.1f}\n")
        print(table_text)
        return
    rows = []
    with tempfile.TemporaryDirectory(prefix="robots-") as tmp:
        os.environ["CASMECH_ALLOWED_DIRS"] = str(robots_folder())
        for name in args.robots:
            folder = Path(tmp) / name
            folder.mkdir()
            if args.stages:
                robot = Robot(name, folder)
                q0, v0 = robot.draw_state(np.random.default_rng(args.seed))
                print(stages_report(name, robot.write_casmech(q0, v0, stops=False), 1e-7),
                      "\n", flush=True)
                continue
            try:
                prepared = prepare(name, folder, args.seed, log)
                rows.append(measure(prepared, args.repeats, min(args.builds, args.repeats),
                                    log))
            except Exception as failure:  # noqa: BLE001 - reported; the other robots run
                log(f"{name} failed: {type(failure).__name__}: {failure}")
    print(f"\nStarted {started}; load at the end {os.getloadavg()[0]:.1f}\n")
    if rows:
        print(table(rows))


if __name__ == "__main__":
    main()
