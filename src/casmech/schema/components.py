"""Components and instances (docs/components.md): a model composed of reusable parts.

`compose(document, overrides)` is the one stage that turns a document using `components:`,
`instances:`, `repeat` or `{expr}` names into an ordinary ResolvedModel:

1. the document is validated as written (structure errors at their place, once);
2. its parameters are evaluated (with the `--set` overrides that name no instance);
3. `repeat` items and `{expr}` names are expanded (schema/repeat.py);
4. every instance resolves its component as a model of its own: the instance's parameter values
   (expressions of the parent's parameters) and `--set <instance>.<name>` overrides replace the
   component's defaults, so each finding inside a component is located in the component's own
   file (or inline block) and is prefixed with the instance; then its members are placed in the
   instance frame and named `<instance>.<member>` (schema/placement.py);
5. the parent's own bodies, joints and forces are resolved with the instances' members known,
   so joints may connect `leg1.foot` to `trunk`; the model lists its own members first, then
   each instance's in order. Parameters of instances appear as `<instance>.<name>`.
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping
from dataclasses import field, replace
from pathlib import Path as FilePath
from typing import Any

from casmech.core import traced
from casmech.core.records import record
from casmech.errors import Diagnostic, ModelError, Source, UsageError, did_you_mean
from casmech.schema import files, placement, repeat, spec
from casmech.schema.bodies import orientation, rotation_matrix
from casmech.schema.checker import NAME, WHY_GROUND
from casmech.schema.force_laws import StateChecker as BaseChecker
from casmech.schema.loader import Document, Path, SourceMap, load_file
from casmech.schema.resolved import GROUND, ResolvedModel
from casmech.schema.semantic import resolve_model
from casmech.schema.spec_errors import validate

PREFIX = re.compile(r"^in instances? (.+?) \(component (.+?)\): (.*)$", re.S)
ALL = 6  # instance names listed in a message before '...'


# ----------------------------------------------------------------------------- checker
class ComposedChecker(BaseChecker):
    """The parent's Checker, knowing the instances' members and naming them in its messages."""

    def __init__(self, document: Document, overrides, members: Members | None = None,
                 symbols: Mapping[str, Any] | None = None,
                 given: Mapping[str, Any] | None = None):
        super().__init__(document, overrides, symbols)
        self.given = dict(given or {})
        self.instances: dict[str, str] = {}
        self.failed: set[str] = set()
        if members is not None:
            self.instances = dict(members.instances)
            self.failed = set(members.failed)
            self.bodies.update({b.name: b for b in members.bodies})
            for item in members.joints:
                self.joint_types[item.name] = item.type
                if hasattr(item, "body_i"):
                    self.joint_bodies[item.name] = (item.body_i, item.body_j)

    def reference(self, path: Path, name: str, known, what: str) -> bool:
        prefixes = owners_of(name)  # by set lookups: a model may have thousands of instances
        if any(prefix in self.failed for prefix in prefixes):
            return False  # the instance's own findings are reported; no follow-up errors
        if name in known or "." not in name or not self.instances:
            return super().reference(path, name, known, what)
        owners = [prefix for prefix in prefixes if prefix in self.instances]
        if not owners:
            head = name.split(".")[0]
            hint = did_you_mean(name, known) or did_you_mean(head, self.instances)
            self.error("E300", path, f"unknown {what} '{name}': there is no instance '{head}'",
                       hint=hint or f"instances: {listing(list(self.instances))}")
            return False
        owner = max(owners, key=len)
        mine = [k for k in known if str(k).startswith(owner + ".")]
        hint = did_you_mean(name, mine) or (f"its members: {listing(mine)}" if mine else None)
        self.error("E300", path, f"unknown {what} '{name}': instance {owner} (component "
                   f"{self.instances[owner]}) has no {what} '{name[len(owner) + 1:]}'", hint=hint)
        return False


def owners_of(name: str) -> list[str]:
    """'a.b.c' -> ['a', 'a.b']: the instance paths a member name may belong to."""
    parts = name.split(".")
    return [".".join(parts[:k]) for k in range(1, len(parts))]


def listing(names: list[str]) -> str:
    return ", ".join(names[:ALL]) + (", ..." if len(names) > ALL else "")


# ----------------------------------------------------------------------------- context
@record
class Scope:
    """The components an instance may use: name -> (definition, document it is written in)."""

    definitions: Mapping[str, tuple[Any, Document]] = field(default_factory=dict)


@record(frozen=False)
class Context:
    stack: tuple[tuple[tuple, str], ...] = ()  # (key, name) of the components being expanded
    files: dict[str, Document | list[Diagnostic]] = field(default_factory=dict)
    # inline components as documents, made once per load: (id of the home document, name) ->
    # (home, document); the home is kept so that its id stays its own
    inline: dict[tuple[int, str], tuple[Document, Document]] = field(default_factory=dict)
    budget: repeat.Budget = field(default_factory=repeat.Budget)  # items left to make

    def push(self, key: tuple, name: str) -> Context:
        return Context((*self.stack, (key, name)), self.files, self.inline, self.budget)


@record(frozen=False)
class Members:
    bodies: list = field(default_factory=list)
    joints: list = field(default_factory=list)
    forces: list = field(default_factory=list)
    parameters: dict[str, float] = field(default_factory=dict)
    instances: dict[str, str] = field(default_factory=dict)  # instance path -> component
    failed: set[str] = field(default_factory=set)  # instances with findings
    files: dict[str, str] = field(default_factory=dict)  # component file -> text


# ----------------------------------------------------------------------------- documents
def with_bodies(document: Document, always: bool = False) -> Document:
    """`bodies:` may be left out when instances give the bodies (and in inline components)."""
    data = document.data
    if data.get("bodies") is not None or not (always or "instances" in data):
        return document
    return replace(document, data={**data, "bodies": []})


def inline_document(document: Document, name: str) -> Document:
    """An inline component as a model document of its own (same file, same lines)."""
    root = ("components", name)

    def rooted(table: dict) -> dict:
        return {path[2:]: entry for path, entry in table.items() if path[:2] == root}

    source_map = SourceMap(rooted(document.source_map.values), rooted(document.source_map.keys),
                           rooted(document.source_map.scalars))
    data = {"casmech": 1, "name": name, **document.data["components"][name]}
    return with_bodies(Document(data, document.file, document.text, source_map), always=True)


def file_document(context: Context, document: Document, name: str, ref):
    """(the component file's document or None, findings) — read once per load. The file must
    be in the model's folder and a regular file of at most files.MAX_MODEL_BYTES."""
    where = ("components", name, "file")
    try:
        path = str(files.resolve(document.file, ref.file))
    except files.NotAllowed as error:
        return None, [Diagnostic("E305", f"components.{name}.file", f"component file "
                                 f"'{ref.file}': {error.reason}", document.locate(where),
                                 hint=error.hint)]
    except FileNotFoundError:
        path = str(FilePath(document.file).parent / ref.file)
    if path not in context.files:
        context.files[path] = _read_component(document, name, ref, path)
    found = context.files[path]
    return (None, found) if isinstance(found, list) else (found, [])


def _read_component(document: Document, name: str, ref, path: str):
    """The component file's document, or its findings (located at `file:` when it cannot be
    read or is too large, in the file itself otherwise)."""
    where = ("components", name, "file")
    try:
        size = os.stat(path).st_size
        if size > files.MAX_MODEL_BYTES:
            return [Diagnostic("E306", f"components.{name}.file", f"component file "
                               f"'{ref.file}' is larger than {files.MAX_MODEL_BYTES >> 20} MiB",
                               document.locate(where), got=f"{size} bytes",
                               hint="split it into smaller components")]
        return with_bodies(load_file(path))
    except (UsageError, OSError) as error:
        message = f"cannot read component file '{ref.file}': {_reason(error)}"
        return [Diagnostic("E300", f"components.{name}.file", message, document.locate(where),
                           hint="the path is relative to this file")]
    except ModelError as error:
        return error.diagnostics


def _reason(error: Exception) -> str:
    if isinstance(error, FileNotFoundError) or "no such file" in str(error):
        return "no such file"
    return getattr(error, "strerror", None) or str(error)


def component_key(document: Document, name: str, ref) -> tuple:
    if isinstance(ref, spec.ComponentFile):
        return ("file", str(FilePath(FilePath(document.file).parent / ref.file).resolve()))
    return ("inline", document.file, name)


def with_values(document: Document, values: Mapping[str, Any]) -> Document:
    parameters = {**document.data.get("parameters", {}), **values}
    return replace(document, data={**document.data, "parameters": parameters})


# ----------------------------------------------------------------------------- messages
def scoped(names: list[str], component: str, diagnostic: Diagnostic) -> Diagnostic:
    """The finding prefixed with the instance(s) it was found in."""
    match = PREFIX.match(diagnostic.message)
    full, message = names, diagnostic.message
    if match:
        full = [f"{o}.{i}" for o in names for i in match.group(1).split(", ")]
        component, message = match.group(2), match.group(3)
    plural = "s" if len(full) > 1 else ""
    path = diagnostic.path
    if path.startswith("--set ") and len(names) == 1:
        path = f"--set {names[0]}.{path[6:]}"
    return replace(diagnostic, path=path, message=f"in instance{plural} {listing(full)} "
                   f"(component {component}): {message}")


def grouped(findings: list[tuple[str, str, Diagnostic]]) -> list[Diagnostic]:
    """The same finding in several instances of one component is reported once."""
    groups: dict[tuple, list[str]] = {}
    for instance, component, diagnostic in findings:
        groups.setdefault((component, diagnostic), []).append(instance)
    return [scoped(names, component, d) for (component, d), names in groups.items()]


# ----------------------------------------------------------------------------- instances
class Instances:
    """Resolves the instances of one (expanded) document into Members."""

    def __init__(self, document: Document, check, scope: Scope, context: Context,
                 overrides: Mapping[str, Mapping[str, str]],
                 symbols: Mapping[str, Mapping[str, Any]] | None = None):
        self.doc, self.check, self.scope, self.context = document, check, scope, context
        self.overrides = overrides
        self.symbols = symbols or {}  # instance -> its symbolic parameters (name -> symbol)
        self.members = Members()
        self.found: list[Diagnostic] = []
        self.inner: list[tuple[str, str, Diagnostic]] = []

    def error(self, code: str, path: Path, message: str, source: Source | None = None,
              **extra) -> None:
        self.check.error(code, path, message, source=source or self.doc.locate(path), **extra)

    def run(self, instances) -> None:
        first: dict[str, int] = {}
        for index, given in enumerate(instances):
            path = ("instances", index)
            if self.valid_name(path, given.name, first) and not self.instance(path, given):
                self.members.failed.add(given.name)
        unknown = [name for name in self.overrides if name not in first]
        for name in unknown:
            hint = did_you_mean(name, first) or f"instances: {listing(list(first)) or 'none'}"
            self.check.error("E300", f"--set {name}.{next(iter(self.overrides[name]))}",
                             f"unknown instance '{name}'", hint=hint)
        for name in [name for name in self.symbols if name not in first]:
            hint = did_you_mean(name, first) or f"instances: {listing(list(first)) or 'none'}"
            self.check.error("E300", f"symbolic {name}.{next(iter(self.symbols[name]))}",
                             f"unknown instance '{name}'", hint=hint)
        self.found += grouped(self.inner)

    def valid_name(self, path: Path, name: str, first: dict[str, int]) -> bool:
        where = (*path, "name")
        if not NAME.match(name):
            self.error("E303", where, f"invalid instance name '{name}'",
                       expected="letters, digits and '_', not starting with a digit")
        elif name == GROUND:
            self.error("E302", where, "'ground' is a reserved name", hint=WHY_GROUND)
        elif name in first:
            line = self.doc.locate(("instances", first[name])).line
            self.error("E301", where, f"duplicate instance name '{name}' (first at line {line})")
        else:
            first[name] = path[1]
            return True
        return False

    def instance(self, path: Path, given: spec.Instance) -> bool:
        """Resolve, place and add one instance; False when it has findings."""
        if self.context.budget.exhausted:  # the model is too large (reported once, E105)
            return False
        definition = self.scope.definitions.get(given.component)
        if definition is None:
            hint = did_you_mean(given.component, self.scope.definitions)
            self.error("E300", (*path, "component"), f"in instance {given.name}: unknown "
                       f"component '{given.component}'", hint=hint or "components: " +
                       (listing(list(self.scope.definitions)) or "none (add a components: map)"))
            return False
        ref, home = definition
        key = component_key(home, given.component, ref)
        chain = [name for k, name in self.context.stack]
        if key in [k for k, _ in self.context.stack]:
            cycle = " -> ".join(chain[[k for k, _ in self.context.stack].index(key):]
                                + [given.component])
            self.error("E103", (*path, "component"), f"in instance {given.name}: component "
                       f"cycle {cycle}", hint="a component cannot contain itself")
            return False
        values = {name: self.check.number((*path, "parameters", name), value)
                  for name, value in given.parameters.items()}
        frame = self.frame(path, given)
        document, found = self.document(home, given.component, ref)
        self.inner += [(given.name, given.component, d) for d in found]
        if document is None or frame is None or None in values.values():
            return False
        document = self.parameters(path, given, document, values)
        if document is None:
            return False
        scope = self.scope if isinstance(ref, spec.Component) else None
        sets = self.overrides.get(given.name, {})
        model, found, instances = compose_document(
            document, sets, self.context.push(key, given.component), scope,
            self.symbols.get(given.name),
            {name: v for name, v in values.items() if traced.is_traced(v)})
        self.inner += [(given.name, given.component, d) for d in found]
        if model is not None:
            self.add(given, model, instances, frame)
        return model is not None

    def document(self, home: Document, name: str, ref):
        if isinstance(ref, spec.ComponentFile):
            return file_document(self.context, home, name, ref)
        key = (id(home), name)
        if key not in self.context.inline:  # one scan of the home's source map per component
            self.context.inline[key] = (home, inline_document(home, name))
        return self.context.inline[key][1], []

    def frame(self, path: Path, given: spec.Instance) -> placement.Frame | None:
        origin = self.check.vector((*path, "position"), given.position)
        p = orientation(self.check, (*path, "orientation"), given.orientation)
        if origin is None or p is None:
            return None
        return placement.Frame(origin, p, rotation_matrix(p))

    def parameters(self, path: Path, given: spec.Instance, document: Document,
                   values: Mapping[str, float]) -> Document | None:
        """The component's document with the instance's values; checks names and required."""
        declared = document.data.get("parameters")
        declared = declared if isinstance(declared, dict) else {}
        ok = True
        for name in values.keys() - declared.keys():
            ok = False
            hint = did_you_mean(name, declared) or "its parameters: " + (
                listing(list(declared)) or "none")
            self.error("E300", (*path, "parameters", name), f"in instance {given.name}: "
                       f"component {given.component} has no parameter '{name}'", hint=hint,
                       source=self.doc.locate_key((*path, "parameters", name)))
        sets = self.overrides.get(given.name, {})
        for name, value in declared.items():
            if value is None and name not in values and name not in sets:
                ok = False
                line = document.locate_key(("parameters", name))
                self.error("E100", path, f"in instance {given.name}: component "
                           f"{given.component} needs a value for its parameter '{name}'",
                           hint=f"add parameters: {{{name}: ...}} to the instance (declared at "
                                f"{line})")
        given_by_set = {name: sets[name] for name in sets if declared.get(name, 0) is None}
        written = {name: traced.value(v) for name, v in values.items()}  # traced: Checker.given
        return with_values(document, {**written, **given_by_set}) if ok else None

    def add(self, given: spec.Instance, model: ResolvedModel, instances: Mapping[str, str],
            frame: placement.Frame) -> None:
        bodies, joints, forces = placement.place(frame, given.name, model)
        members = self.members
        members.bodies += bodies
        members.joints += joints
        members.forces += forces
        members.parameters.update({f"{given.name}.{k}": v for k, v in model.parameters.items()})
        members.instances[given.name] = given.component
        members.instances.update({f"{given.name}.{k}": v for k, v in instances.items()})
        members.files.update(getattr(model, "files", None) or {})
        if not model.file == self.doc.file:
            members.files[model.file] = model.text


# ----------------------------------------------------------------------------- compose
def split_overrides(overrides: Mapping[str, str] | None):
    """(the document's own overrides, {instance: {rest: value}})."""
    own, nested = {}, {}
    for name, value in (overrides or {}).items():
        head, dot, rest = name.partition(".")
        if dot:
            nested.setdefault(head, {})[rest] = value
        else:
            own[name] = value
    return own, nested


def definitions(document: Document, given: spec.ModelSpec, scope: Scope | None) -> Scope:
    if scope is not None:  # an inline component sees the components of its file
        return scope
    return Scope({name: (ref, document) for name, ref in given.components.items()})


def compose_document(document: Document, overrides, context: Context,
                     scope: Scope | None = None, symbols: Mapping[str, Any] | None = None,
                     values: Mapping[str, Any] | None = None):
    """(model or None, findings, {instance path: component}) of one model document;
    `symbols`: its symbolic parameters (an instance's as `<instance>.<name>`), `values`: the
    traced numbers an instance gives its parameters (the document holds their values)."""
    document = with_bodies(document)
    given, found = validate(document)
    if given is None:
        return None, [*document.diagnostics, *found], {}
    own, nested = split_overrides(overrides)
    own_symbols, nested_symbols = split_overrides(symbols)
    check = ComposedChecker(document, own, symbols=own_symbols, given=values)
    check.parameter_values(given.parameters)
    if check.found:
        return None, [*document.diagnostics, *check.found], {}
    expanded, found = repeat.expand(document, check.parameters, context.budget)
    if expanded is None:
        return None, [*document.diagnostics, *found], {}
    given, found = validate(expanded)
    if given is None:  # pragma: no cover - substitution keeps every value's type
        return None, found, {}
    check = ComposedChecker(expanded, own, symbols=own_symbols, given=values)
    check.parameter_values(given.parameters)
    instances = Instances(expanded, check, definitions(expanded, given, scope), context, nested,
                          nested_symbols)
    instances.run(given.instances)
    members = instances.members
    check = ComposedChecker(expanded, own, members, own_symbols, values)
    model = resolve_model(check, given)
    found = repeat.relabel([*instances.check.found, *check.found], expanded)
    found = [*document.diagnostics, *found, *instances.found]
    if model is None or found:
        return None, found, members.instances
    return merged(model, members), [], members.instances


def merged(model: ResolvedModel, members: Members) -> ResolvedModel:
    extra = {"files": members.files} if hasattr(model, "files") else {}
    return replace(model, bodies=(*model.bodies, *members.bodies),
                   joints=(*model.joints, *members.joints),
                   forces=(*model.forces, *members.forces),
                   parameters={**model.parameters, **members.parameters}, **extra)


def compose(document: Document, overrides: Mapping[str, str] | None,
            symbols: Mapping[str, Any] | None = None):
    """(the composed ResolvedModel or None, every finding); `symbols`: the parameters (an
    instance's as `<instance>.<name>`) evaluated as traced numbers."""
    top = (("file", str(FilePath(document.file).resolve())), FilePath(document.file).name)
    model, found, _ = compose_document(document, overrides, Context((top,)), symbols=symbols)
    return model, found
