"""Layering of casmech's packages, read from the source by ast (docs/architecture.md, Layout).

Every import counts: at module level, inside functions and under `if TYPE_CHECKING:`. A unit
(a subpackage of casmech, or a top-level module) imports only units of lower layers and
itself; no module reaches itself through others (no cycle of modules, inside a package
either); no module imports a private name (`_name`) of another module, by `from ... import`
or as an attribute of an imported module; optimal/ takes formulations/ through its protocol
and registry only."""

import ast
from functools import cache
from pathlib import Path

import pytest

from tests.conftest import ROOT

SRC = ROOT / "src" / "casmech"

# low to high; a unit imports only units of earlier rows and its own
LAYERS = (
    ("errors", "core"),  # expressions, rotations, the registry table, the results columns
    ("numerics",),  # least squares, the saddle solve, sums of elements: CasADi only
    ("elements",),  # primitives, joint types and their coordinates, force types
    ("schema",),  # YAML -> ResolvedModel
    ("importers",),  # other formats -> casmech YAML (checked by the schema)
    ("model",),  # ResolvedModel -> ModelIR, the model data
    ("equations",),  # the system functions of one model (the builder)
    ("formulations",),  # rp, romega, joint: DAEs, ODEs, the prescribed step
    ("backends",),  # compiled libraries: generate, build, cache, load
    ("runtime",),  # analyses over the functions
    ("optimal",),  # sensitivities, estimation, optimal control
    ("fmu",),  # FMI export: the model's ODE, outputs and start as C in an FMU
    ("io",),  # results files, plots, animations
    ("study",),  # parameter studies
    ("api",),  # the Python API
    ("cli",),  # the command line
    ("casmech", "__main__"),  # the package's own __init__ (lazy public names); python -m casmech
)
LAYER = {unit: k for k, row in enumerate(LAYERS) for unit in row}


def module_name(path: Path) -> str:
    parts = ["casmech", *path.relative_to(SRC).with_suffix("").parts]
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {module_name(path): path for path in SRC.rglob("*.py")}


@cache
def imports(path: Path, name: str | None = None) -> list[tuple[str, str | None, int]]:
    """(module imported, name imported from it or None, line) for every casmech import of a
    file (the module `name`, by default its own under src/casmech): a name that is itself a
    module counts as that module (parsed once per file)."""
    package = (name or module_name(path)).split(".")
    if path.name != "__init__.py":
        package = package[:-1]
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [(alias.name, None, node.lineno) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = package[:len(package) - node.level + 1] if node.level else []
            module = ".".join([*base, *([node.module] if node.module else [])])
            for alias in node.names:
                if f"{module}.{alias.name}" in MODULES:
                    found.append((f"{module}.{alias.name}", None, node.lineno))
                else:
                    found.append((module, alias.name, node.lineno))
    return [item for item in found if item[0].split(".")[0] == "casmech"]


def unit(module: str) -> str:
    """casmech.equations.eom -> equations; casmech.api -> api; casmech -> casmech."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "casmech"


def test_every_unit_has_a_layer():
    assert {unit(name) for name in MODULES} - set(LAYER) == set()


def test_no_upward_import():
    upward = [f"{path.relative_to(SRC)}:{line}: {unit(module_name(path))} imports {target}"
              for path in MODULES.values() for target, _, line in imports(path)
              if LAYER[unit(target)] > LAYER[unit(module_name(path))]]
    assert upward == []


def module_graph() -> dict[str, set[str]]:
    return {name: {target for target, _, _ in imports(path) if target != name}
            for name, path in MODULES.items()}


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(node):
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for other in graph.get(node, ()):
            if other not in graph:
                continue
            if other not in index:
                visit(other)
                low[node] = min(low[node], low[other])
            elif other in on_stack:
                low[node] = min(low[node], index[other])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


def test_cycles_are_found():
    """The cycle search on a graph with one (a test that cannot pass vacuously)."""
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_no_module_reaches_itself():
    assert cycles(module_graph()) == []


def private_uses(path: Path) -> list[str]:
    """`from casmech.x import _name` and `module._name` of an imported casmech module."""
    tree = ast.parse(path.read_text(), str(path))
    bound = {}  # local name -> casmech module it names
    found = [f"{line}: {target}.{name}" for target, name, line in imports(path)
             if name is not None and name.startswith("_") and not name.startswith("__")]
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom | ast.Import):
            for alias in node.names:
                full = (f"{node.module}.{alias.name}" if isinstance(node, ast.ImportFrom)
                        and node.module else alias.name)
                if full in MODULES:
                    bound[alias.asname or alias.name.split(".")[-1]] = full
    for node in ast.walk(tree):
        if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
                and node.value.id in bound and node.attr.startswith("_")
                and not node.attr.startswith("__")):
            found.append(f"{node.lineno}: {bound[node.value.id]}.{node.attr}")
    return found


def test_no_module_imports_a_private_name_of_another():
    found = {str(path.relative_to(SRC)): uses for path in MODULES.values()
             if (uses := private_uses(path))}
    assert found == {}


def test_private_names_are_found(tmp_path):
    """The private-name search on a file using both forms."""
    file = SRC / "runtime" / "_layering_probe.py"
    file.write_text("from casmech.errors import _private\nfrom casmech.core import euler\n"
                    "x = euler._helper\n")
    try:
        MODULES[module_name(file)] = file
        assert private_uses(file) == ["1: casmech.errors._private", "3: casmech.core.euler._helper"]
    finally:
        MODULES.pop(module_name(file), None)
        file.unlink()


# what optimal/ takes of formulations/: the protocol and its registry; optimal control,
# sensitivities and estimation take a registered Formulation (FORMULATIONS["joint"].controlled,
# FORMULATIONS["rp"].residual), never a formulation's own modules (docs/architecture.md)
FORMULATION_ENTRIES = {"casmech.formulations", "casmech.formulations.protocol",
                       "casmech.formulations.registry"}


def formulation_modules(found: list[tuple[str, str | None, int]]) -> list[str]:
    """The imports among `found` of a module of formulations/ other than its entries."""
    return [f"{line}: {target}" for target, _, line in found
            if unit(target) == "formulations" and target not in FORMULATION_ENTRIES]


def test_optimal_takes_formulations_through_the_protocol():
    found = {str(path.relative_to(SRC)): uses for name, path in MODULES.items()
             if unit(name) == "optimal" and (uses := formulation_modules(imports(path)))}
    assert found == {}


def test_a_formulation_module_imported_by_optimal_is_found(tmp_path):
    """The rule above on a module of optimal/ importing joint_system (a test that cannot pass
    vacuously), in both import forms, next to the registry it may import."""
    probe = tmp_path / "probe.py"
    probe.write_text("from casmech.formulations.joint_system import build\n"
                     "from casmech.formulations.registry import FORMULATIONS\n"
                     "from casmech.formulations import joint_start, protocol\n")
    assert formulation_modules(imports(probe, "casmech.optimal.probe")) == [
        "1: casmech.formulations.joint_system", "3: casmech.formulations.joint_start"]


def test_no_module_is_over_500_lines():
    """Modules stay small enough to hold one job."""
    sizes = {str(path.relative_to(SRC)): len(path.read_text().splitlines())
             for path in SRC.rglob("*.py")}
    assert {path: n for path, n in sizes.items() if n > 500} == {}


def test_the_build_cache_digests_every_package_the_generated_code_depends_on():
    """backends/cache.source_digest covers backends/ and every unit below it that its code
    imports (an edit there must not reuse a stale build); errors.py only words messages."""
    from casmech.backends import cache

    needed = {unit(target) for name, path in MODULES.items() if unit(name) == "backends"
              for target, _, _ in imports(path)}
    stack = list(needed)
    while stack:
        for name, path in MODULES.items():
            if unit(name) == stack[-1]:
                for target, _, _ in imports(path):
                    if unit(target) not in needed:
                        needed.add(unit(target))
                        stack.insert(0, unit(target))
        stack.pop()
    covered = {*cache.SOURCE_PACKAGES, *(name.removesuffix(".py") for name in cache.SOURCE_MODULES)}
    assert needed - {"errors"} <= covered


def test_the_build_cache_digests_every_module_that_keys_its_own_builds():
    """A module outside the digested packages that builds a graph compiled under a key of its
    own (backends.library.compile_keyed: the graph is not in the key) is digested too."""
    from casmech.backends import cache

    covered = {*cache.SOURCE_PACKAGES, *(name.removesuffix(".py") for name in cache.SOURCE_MODULES)}
    keyed = {str(path.relative_to(SRC).with_suffix("")) for path in SRC.rglob("*.py")
             if "compile_keyed(" in path.read_text()}
    assert keyed, "no module calls compile_keyed: the test looks for nothing"
    assert {name for name in keyed if name.split("/")[0] not in covered and name not in covered} \
        == set()


@pytest.mark.parametrize("unit_name", [u for row in LAYERS for u in row if u != "casmech"])
def test_each_unit_exists(unit_name):
    assert (SRC / unit_name).is_dir() or (SRC / f"{unit_name}.py").is_file()
