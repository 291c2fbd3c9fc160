"""Fixtures of the code-generation tests: one small model (tests/helpers/codegen_model.yaml: a
driven revolute, a spherical joint, a spring-damper and a torque, so every system function has
content) built once per session, into a private cache, with warnings as errors."""

from pathlib import Path

import pytest

import casmech
from casmech.backends import codegen

MODEL = Path(__file__).with_name("codegen_model.yaml")
# -O0: the fastest build (tests measure agreement, not speed); -Wall -Werror: the issue asks
# that the generated C compile cleanly with them.
FLAGS = ("-O0", "-Wall", "-Werror")


def model_libraries(root: Path) -> set:
    """The cache entries under `root` of models' libraries: all but the C drivers of
    backends.rk_library (DOP853's and the rows' loop: one entry each per machine, built by the
    first compiled run of a process whose cache lacks it, so present or not by which tests ran
    before)."""
    import json

    from casmech.backends import cache, manifest

    drivers = {"rk driver", "rows driver"}
    return {entry for entry in cache.entries(root)
            if json.loads((entry / manifest.MANIFEST).read_text()).get("model") not in drivers}


def counted_builds(monkeypatch, module) -> list:
    """Every call of `module`.build_libraries (the C compiler runs only inside it), recorded
    as its positional arguments: how tests count builds."""
    calls, original = [], module.build_libraries

    def counting(*args, **kwargs):
        calls.append(args)
        return original(*args, **kwargs)

    monkeypatch.setattr(module, "build_libraries", counting)
    return calls


@pytest.fixture
def builds(monkeypatch) -> list:
    """Every cache entry built from here on (a library of a model, of the joint functions, of
    a joint space's function, ...): the keys cache.lookup's build callable ran for."""
    from casmech.backends import cache

    calls, lookup = [], cache.lookup

    def counting(entry, build, root=None):
        return lookup(entry, lambda directory: calls.append(entry) or build(directory), root)

    monkeypatch.setattr(cache, "lookup", counting)
    return calls


@pytest.fixture(scope="session")
def cache_root(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("casmech_cache")


@pytest.fixture(autouse=True)
def private_cache(cache_root, monkeypatch) -> Path:
    """Every test of a folder whose conftest.py takes these fixtures uses the session's cache,
    never the user's ~/.cache/casmech, and FLAGS."""
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(cache_root))
    monkeypatch.setenv("CASMECH_CFLAGS", " ".join(FLAGS))  # what the CLI builds with
    return cache_root


@pytest.fixture(scope="session")
def toolchain() -> codegen.Toolchain:
    """The C compiler (CI installs gcc: .ci/run); without one the tests that build skip."""
    chain = codegen.Toolchain(flags=FLAGS)
    if not codegen.available(chain):
        pytest.skip(f"no C compiler '{chain.compiler}'")
    return chain


@pytest.fixture(scope="session")
def model():
    return casmech.load(MODEL)


@pytest.fixture(scope="session")
def interpreted(model):
    return casmech.compile(model, "interpreted")


@pytest.fixture(scope="session")
def build_dir(model, toolchain, cache_root, tmp_path_factory) -> Path:
    """`casmech compile`'s output for the model (through the session cache)."""
    out = tmp_path_factory.mktemp("build")
    codegen.export(model, out, toolchain, root=cache_root)
    return out


@pytest.fixture(scope="session")
def compiled(model, toolchain, cache_root, build_dir):
    return codegen.compiled(model, toolchain, root=cache_root)
