"""simEngine3D (UW-Madison ME751) model `.mdl` and analysis-control `.acf` JSON -> casmech.

The course's model file is JSON: `bodies` (each with `name`, `id`, `r`, `r_dot`, `p`, `p_dot`,
`mass`, `jbar`; ground is id 0, a body named ground, or `"ground": true`), `constraints` (each
with `type` DP1/DP2/D/CD, `body_i`, `body_j`, the body-frame vectors `a_bar_i`, `a_bar_j`,
`s_bar_p_i`, `s_bar_q_j`, `c`, and `f` with its derivative strings `f_dot`, `f_ddot`), and
`gravity`. Students' variants of the key names are accepted (tables below). The derivative
strings are ignored with a warning: casmech derives them from `f`. Composite constraints
(spherical/revolute/universal/cylindrical/translational, given by body-frame points and axes)
become casmech's composite joints placed from the initial pose. The `.acf` gives `analysis:`.
Comments: JSON has none, but a `"comment"`/`"description"` string on any object is kept.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from casmech.errors import Diagnostic, ModelError, Source
from casmech.importers.adm_frames import tidy
from casmech.importers.emit import Imported, Item
from casmech.importers.simengine_read import Located, composite_joint, rotation
from casmech.schema import files

# casmech key <- accepted simEngine3D spellings
BODY_KEYS = {"r": ("r", "r0", "position"), "p": ("p", "p0", "euler_parameters"),
             "r_dot": ("r_dot", "rdot", "r_dot0", "velocity"),
             "p_dot": ("p_dot", "pdot", "p_dot0"), "mass": ("mass", "m"),
             "inertia": ("jbar", "j_bar", "J", "Jbar", "inertia")}
ROW_KEYS = {"body_i": ("body_i", "body1", "bodyi", "ibody", "body_1"),
            "body_j": ("body_j", "body2", "bodyj", "jbody", "body_2"),
            "a_i": ("a_bar_i", "a1", "aiBAR", "a_i", "abar_i"),
            "a_j": ("a_bar_j", "a2", "ajBAR", "a_j", "abar_j"),
            "s_i": ("s_bar_p_i", "s_bar_i", "sP_i", "sPi", "s_i", "sbar_p_i", "sP1"),
            "s_j": ("s_bar_q_j", "s_bar_j", "sQ_j", "sQj", "s_j", "sbar_q_j", "sQ2"),
            "c": ("c", "coord"), "f": ("f", "fun", "f_t", "ft")}
DERIVATIVES = ("f_dot", "f_ddot", "fdot", "fddot", "df", "ddf", "f_d", "f_dd")
NOTES = ("comment", "comments", "description", "note")
# basic constraint -> the keys it takes (besides body_i, body_j, f)
BASIC = {"dp1": ("a_i", "a_j"), "dp2": ("a_i", "s_i", "s_j"), "d": ("s_i", "s_j"),
         "cd": ("c", "s_i", "s_j")}
ANALYSIS_KEYS = {"type": ("simulation", "analysis", "type", "mode", "sim_type"),
                 "t_end": ("t_end", "tend", "end_time", "t_final", "tfinal", "duration"),
                 "output_step": ("output_step", "step_size", "stepsize", "h", "time_step",
                                 "dt", "timestep"),
                 "rtol": ("rtol", "tolerance", "tol"), "atol": ("atol",)}
ANALYSIS_TYPES = {"kinematics": "kinematics", "kinematic": "kinematics",
                  "dynamics": "dynamics", "dynamic": "dynamics",
                  "inverse_dynamics": "inverse_dynamics", "inverse dynamics": "inverse_dynamics",
                  "assembly": "assembly", "statics": "statics", "equilibrium": "statics"}


def f_expression(text: str) -> str:
    """A MATLAB/NumPy f(t) string as a casmech expression: '@(t)' dropped, 'np.'/'math.'
    prefixes dropped, '^' as '**'."""
    text = re.sub(r"^\s*@\s*\(\s*t\s*\)", "", str(text))
    text = re.sub(r"\b(?:np|numpy|math)\.", "", text)
    return text.replace("^", "**").replace(".*", "*").replace("./", "/").strip() or "0"


def _ground(body: dict) -> bool:
    return body.get("ground") is True or body.get("id") == 0 and "r" not in body or \
        str(body.get("name", "")).lower() == "ground"


def _name(text: str, fallback: str) -> str:
    name = re.sub(r"\W", "_", str(text)).strip("_") or fallback
    return name if re.match(r"[A-Za-z_]", name) else f"b_{name}"


class Translator:
    def __init__(self, located: Located):
        self.at = located
        self.model = Imported(name="", description="", header=[])
        self.names: dict[Any, str] = {}  # body id or name -> casmech name
        self.frames: dict[str, tuple[np.ndarray, np.ndarray]] = {}  # name -> (r, A) at t = 0

    def body(self, k: int, body: dict) -> None:
        at, path = self.at, ("bodies", k)
        if _ground(body):
            for key in (body.get("id"), body.get("name")):
                self.names[key] = "ground"
            self.frames["ground"] = (np.zeros(3), np.eye(3))
            return
        name = _name(body.get("name", f"body_{body.get('id', k)}"), f"body_{k}")
        self.names[body.get("id", k)] = self.names[body.get("name", name)] = name
        r = at.vector(body, path, BODY_KEYS["r"], 3)
        p = at.vector(body, path, BODY_KEYS["p"], 4, default=[1, 0, 0, 0])
        if abs(np.linalg.norm(p) - 1) > 1e-9:
            at.warn(at.key_path(body, path, BODY_KEYS["p"]),
                    f"p of body {name} has norm {np.linalg.norm(p):.9g}: normalised",
                    hint="casmech needs unit Euler parameters to 1e-9")
        p = p / np.linalg.norm(p)
        a = rotation(p)
        self.frames[name] = (r, a)
        data = {"name": name, "mass": at.number(body, path, BODY_KEYS["mass"]),
                "inertia": at.inertia(body, path, BODY_KEYS["inertia"]), "position": tidy(r),
                "orientation": {"euler_parameters": tidy(p)}}
        r_dot = at.vector(body, path, BODY_KEYS["r_dot"], 3, default=[0, 0, 0])
        p_dot = at.vector(body, path, BODY_KEYS["p_dot"], 4, default=[0, 0, 0, 0])
        if np.any(r_dot):
            data["velocity"] = tidy(r_dot)
        if np.any(p_dot):  # omega (global) = 2 E(p) p_dot
            e0, e = p[0], p[1:]
            skew = np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])
            data["angular_velocity"] = tidy(2 * np.column_stack([-e, skew + e0 * np.eye(3)])
                                            @ p_dot)
        self.unknown_keys(body, path, [*sum(BODY_KEYS.values(), ()), "name", "id", "ground",
                                       *NOTES])
        self.model.bodies.append(Item(data, self.notes(body, f"bodies[{k}] "
                                                             f"(line {at.line(path)})")))

    def notes(self, obj: dict, where: str) -> list[str]:
        return [str(obj[key]) for key in NOTES if key in obj] + [where]

    def unknown_keys(self, obj: dict, path, known) -> None:
        for key in obj:
            if key not in known:
                self.at.warn((*path, key), f"key '{key}' not translated", code="E101")

    def body_ref(self, row: dict, path, key: str) -> str:
        value = self.at.pick(row, path, ROW_KEYS[key])
        if isinstance(value, str) and value.strip().isdigit() and value not in self.names:
            value = int(value)  # some course files quote the ids: "body2": "2"
        if value not in self.names:
            raise self.at.error((*path, key), f"{key} refers to an unknown body '{value}'",
                                "a body id or name from 'bodies'", "E300",
                                got=str(value), hint=f"known: {sorted(map(str, self.names))}")
        return self.names[value]

    def constraint(self, k: int, row: dict) -> None:
        at, path = self.at, ("constraints", k)
        kind = str(at.pick(row, path, ("type",))).lower()
        name = _name(row.get("name", f"{kind}_{k + 1}"), f"c{k + 1}")
        body_i, body_j = self.body_ref(row, path, "body_i"), self.body_ref(row, path, "body_j")
        data = {"name": name, "type": kind, "body_i": body_i, "body_j": body_j}
        for key in (d for d in DERIVATIVES if d in row):
            at.warn((*path, key), f"'{key}' ignored: casmech derives the derivatives of f",
                    code="E101")
        if kind in BASIC:
            for key in BASIC[kind]:
                data[key] = tidy(at.vector(row, path, ROW_KEYS[key], 3))
            data["f"] = f_expression(at.pick(row, path, ROW_KEYS["f"], default="0"))
            at.expression(data["f"], (*path, "f"))
        else:
            data = composite_joint(at, row, path, kind, data, self.frames, ROW_KEYS)
        known = [*sum(ROW_KEYS.values(), ()), *DERIVATIVES, "type", "name", "id", *NOTES]
        self.unknown_keys(row, path, known)
        self.model.joints.append(Item(data, self.notes(row, f"constraints[{k}] {kind.upper()} "
                                                             f"(line {at.line(path)})")))

    def analysis(self, acf: Located) -> None:
        data, settings = acf.data, {}
        for key, spellings in ANALYSIS_KEYS.items():
            value = acf.pick(data, (), spellings, default=None)
            if value is None:
                continue
            if key == "type":
                text = str(value).lower().replace("-", "_")
                if text not in ANALYSIS_TYPES:
                    raise acf.error((next(s for s in spellings if s in data),),
                                    f"unknown analysis '{value}'", "one of "
                                    + ", ".join(sorted(ANALYSIS_TYPES)), "E103")
                settings[key] = ANALYSIS_TYPES[text]
            else:
                settings[key] = acf.number(data, (), spellings)
        start = acf.pick(data, (), ("t_start", "tstart", "t0", "start_time"), default=0)
        if start:
            acf.warn(("t_start",), f"t_start = {start} not translated: casmech starts at 0")
        self.model.analysis = Item(settings, [f"from {Path(acf.file).name}; the step size of "
                                              "simEngine3D's integrator becomes output_step"])


def import_simengine(path: Path) -> Imported:
    """A .mdl (with the .acf of the same name beside it, if any) or an .acf (with the model it
    names, or the .mdl of the same name)."""
    acf_path = path if path.suffix.lower() == ".acf" else path.with_suffix(".acf")
    acf = Located.read(acf_path) if acf_path.is_file() else None
    mdl_path = path
    if path.suffix.lower() == ".acf":
        named = acf.pick(acf.data, (), ("model", "mdl", "model_file"), default=None)
        mdl_path = path.parent / named if named else path.with_suffix(".mdl")
        try:  # beside the .acf or below, as a model's files are (casmech.schema.files)
            mdl_path = files.resolve(str(path), str(named or mdl_path.name), must_exist=False)
        except files.NotAllowed as error:
            raise ModelError([Diagnostic("E305", "model", f"model file '{named}': "
                                         f"{error.reason}", Source(str(path), 1, 1),
                                         hint="import the .mdl directly")]) from None
        if not mdl_path.is_file():
            raise ModelError([Diagnostic("E300", "model", f"no model file {mdl_path}",
                                         Source(str(path), 1, 1), expected="a .mdl beside "
                                         "the .acf, or \"model\": \"file.mdl\" in it",
                                         hint="import the .mdl directly")])
    located = Located.read(mdl_path)
    translator = Translator(located)
    data = located.data
    for k, body in enumerate(located.list(data, ("bodies",))):
        translator.body(k, body)
    for k, row in enumerate(located.list(data, ("constraints",), required=False)):
        translator.constraint(k, row)
    if acf is not None:
        translator.analysis(acf)
    model = translator.model
    model.name = str(data.get("name", mdl_path.stem))
    model.description = f"simEngine3D model {mdl_path.name}"
    model.header = [f"Imported by `casmech import` from the simEngine3D model {mdl_path.name}"
                    + (f" and {Path(acf.file).name}" if acf else "") + ".",
                    *(str(data[key]) for key in NOTES if key in data),
                    "Constraints are written as casmech's basic constraints DP1/DP2/D/CD "
                    "(vectors in body frames);", "f(t) strings are kept, their derivative "
                    "strings dropped (casmech differentiates f).", ""]
    model.gravity = tidy(located.vector(data, (), ("gravity", "g"), 3, default=[0, 0, -9.81]))
    located.known(data, ("name", "bodies", "constraints", "gravity", "g", *NOTES))
    model.warnings = located.warnings + (acf.warnings if acf else [])
    return model
