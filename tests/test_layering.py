"""Layering of the packages (issue 15), read from the source by ast: schema/ never imports
compiler/, the bottom layer (casmech.geometry) no other casmech package, the YAML base classes
(casmech.spec_base) and the registry table (casmech.registry) none either, the joint registry
(casmech.joint_types) only the bottom layer
and the force element registry (casmech.force_types, the built-in types' code casmech.forces)
only those, not even inside a function; no two packages import each other at import time
(module-level imports, through any chain; an import inside a function, done on use, is allowed
to point upwards)."""

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "casmech"


def imported(path: Path, module_level: bool = False) -> set[str]:
    """The casmech modules a file imports (absolute and relative; `module_level`: only the
    statements outside functions, under `if TYPE_CHECKING:` included)."""
    package = ["casmech", *path.relative_to(SRC).parent.parts]
    tree = ast.parse(path.read_text(), str(path))
    names = set()
    for node in (_module_level(tree) if module_level else ast.walk(tree)):
        if isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = package[:len(package) - node.level + 1] if node.level else []
            module = ".".join([*base, *([node.module] if node.module else [])])
            names |= {f"{module}.{alias.name}" for alias in node.names} | {module}
    return {name for name in names if name.split(".")[0] == "casmech"}


def _module_level(tree: ast.Module):
    stack = list(tree.body)
    while stack:
        node = stack.pop()
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda):
            continue
        yield node
        stack.extend(ast.iter_child_nodes(node))


def unit(module: str) -> str:
    """casmech.compiler.eom -> compiler; casmech.api -> api (a top-level module)."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "casmech"


def package_graph() -> dict[str, set[str]]:
    graph: dict[str, set[str]] = {}
    for path in SRC.rglob("*.py"):
        parts = path.relative_to(SRC).parts
        owner = parts[0] if len(parts) > 1 else path.stem
        if owner == "__init__":
            continue
        targets = {unit(name) for name in imported(path, module_level=True)}
        targets -= {owner, "casmech"}
        graph.setdefault(owner, set()).update(targets)
    return graph


# what the force element registry and its code may import (besides third-party libraries)
BOTTOM = {"force_types", "forces", "geometry", "joint_types", "spec_base", "errors",
          "registry"}


@pytest.mark.parametrize("package, forbidden", [
    ("schema", {"compiler", "runtime", "codegen", "optimal", "output", "study", "commands"}),
    ("geometry", set(package_graph()) - {"geometry"}),
    ("joint_types", set(package_graph()) - {"joint_types", "geometry", "registry"}),
    ("registry", set(package_graph()) - {"registry"}),
    ("spec_base", set(package_graph()) - {"spec_base"}),
    ("forces", set(package_graph()) - BOTTOM),
    ("force_types", set(package_graph()) - BOTTOM),
])
def test_a_package_imports_nothing_above_it(package, forbidden):
    files = [SRC / f"{package}.py"] if (SRC / f"{package}.py").exists() else \
        (SRC / package).glob("*.py")
    found = {str(path.relative_to(SRC)): sorted(unit(m) for m in imported(path)
                                               if unit(m) in forbidden)
             for path in files}
    assert {path: units for path, units in found.items() if units} == {}


def test_no_two_packages_import_each_other():
    """The package graph has no cycle (a package reaching itself through others)."""
    graph = package_graph()
    cycles = []
    for start in graph:
        seen, stack = set(), list(graph[start])
        while stack:
            node = stack.pop()
            if node == start:
                cycles.append(start)
                break
            if node not in seen:
                seen.add(node)
                stack.extend(graph.get(node, ()))
    assert cycles == []


def test_no_module_is_over_500_lines():
    """Issue 15: modules stay small enough to hold one job."""
    sizes = {str(path.relative_to(SRC)): len(path.read_text().splitlines())
             for path in SRC.rglob("*.py")}
    assert {path: n for path, n in sizes.items() if n > 500} == {}


def test_the_build_cache_digests_every_package_the_generated_code_depends_on():
    """codegen/cache.source_digest covers compiler/, codegen/ and whatever they import (an
    edit there must not reuse a stale build); errors.py only words messages."""
    from casmech.codegen import cache

    graph, needed, stack = package_graph(), set(), ["compiler", "codegen"]
    while stack:
        node = stack.pop()
        if node not in needed:
            needed.add(node)
            stack.extend(graph.get(node, ()))
    covered = {*cache.SOURCE_PACKAGES, *(name.removesuffix(".py") for name in cache.SOURCE_MODULES)}
    assert needed - {"errors"} <= covered
