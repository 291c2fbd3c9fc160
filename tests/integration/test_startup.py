"""Start-up: importing casmech does no work and pulls in no library a command may not need
(issue 36; benchmarks/cli_startup.py and benchmarks/process_race.py time the processes).

Each check runs in a fresh interpreter and reads what it imported (sys.modules), what casadi
Functions it built and what files casmech's own code opened, so a regression fails without a
timing."""

import json
import subprocess
import sys

import pytest

from tests.conftest import MODELS

# libraries no command needs at `import casmech` / `import casmech.cli`
HEAVY = ("numpy", "casadi", "pydantic", "yaml", "scipy", "matplotlib", "pandas", "dask",
         "distributed", "h5py", "meshio", "tqdm", "filelock", "platformdirs")
# casmech's own modules that only some commands use
COMPILER = ("casmech.backends.codegen", "casmech.backends.build", "casmech.backends.generate",
            "casmech.backends.library", "casmech.backends.cache")


def modules_after(code: str) -> set[str]:
    """The modules a fresh interpreter holds after running `code`."""
    probe = f"{code}\nimport json, sys\nprint(json.dumps(sorted(sys.modules)))"
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    return set(json.loads(done.stdout.splitlines()[-1]))


def loaded(modules: set[str], packages) -> list[str]:
    return sorted(m for m in modules for p in packages if m == p or m.startswith(p + "."))


@pytest.mark.parametrize("code", ["import casmech", "import casmech.cli",
                                  "import casmech; casmech.__version__; dir(casmech)"])
def test_importing_the_package_loads_no_library(code):
    modules = modules_after(code)
    assert "casmech" in modules  # the probe sees the import
    assert loaded(modules, [*HEAVY, *COMPILER, "casmech.api", "casmech.schema",
                            "casmech.runtime", "casmech.study", "casmech.io"]) == []


def test_a_public_name_imports_its_own_module_only():
    """casmech.sweep names the study's API: no Dask, no compiler, no plotting until a study
    runs."""
    modules = modules_after("import casmech; casmech.sweep")
    assert "casmech.study.api" in modules
    assert loaded(modules, ["dask", "distributed", "matplotlib", "pandas", "scipy",
                            *COMPILER]) == []


AUDIT = """
import importlib, json, pkgutil, sys
import casadi
from pathlib import Path
import casmech

ROOT = str(Path(casmech.__file__).parent)
built, opened = [], []
original = casadi.Function.__init__


def where():
    frame = sys._getframe(2)
    return f"{frame.f_code.co_filename}:{frame.f_lineno}"


def counting(self, *args, **kwargs):
    built.append(where())
    original(self, *args, **kwargs)


def hook(event, args):
    # a file opened by casmech's own code (not by the import system reading its modules)
    if event == "open" and sys._getframe(1).f_code.co_filename.startswith(ROOT):
        opened.append(f"{args[0]} at {where()}")


casadi.Function.__init__ = counting
sys.addaudithook(hook)
names = sorted(m.name for m in pkgutil.walk_packages(casmech.__path__, "casmech.")
               if not m.name.endswith(".__main__"))
for name in names:
    importlib.import_module(name)
probe = casadi.SX.sym("x")
casadi.Function("probe", [probe], [probe])  # the counter counts
print(json.dumps({"modules": len(names), "built": built, "opened": opened}))
"""


def test_no_module_builds_a_function_or_reads_a_file_at_import():
    """Work happens when a command asks for it: importing every module of casmech builds no
    casadi Function (the probe's own is the one counted) and opens no file."""
    done = subprocess.run([sys.executable, "-c", AUDIT], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout.splitlines()[-1])
    assert report["modules"] > 100  # walked the whole package
    assert len(report["built"]) == 1 and report["built"][0].startswith("<string>")
    assert report["opened"] == []


def test_a_run_imports_no_study_plotting_or_optimization(tmp_path):
    """`casmech run` of a dynamics model (the joint formulation's tree) loads neither Dask nor
    pandas, plotting, SciPy's optimizers, the importers or the optimal-control layer, nor
    the schema of a replayed run's record (only `--replay` reads one), nor difflib (the
    suggestions of an error message)."""
    code = ("import sys; from casmech import cli; "
            f"code = cli.main(['run', {str(MODELS / 'double_pendulum.yaml')!r}, '--t-end', "
            f"'0.05', '--out', {str(tmp_path / 'out')!r}, '--mode', 'interpreted', '--quiet'])"
            "\nassert code == 0, code")
    modules = modules_after(code)
    assert (tmp_path / "out" / "results.csv").is_file()
    assert loaded(modules, ["dask", "distributed", "pandas", "matplotlib", "scipy.optimize",
                            "h5py", "meshio", "casmech.study", "casmech.optimal",
                            "casmech.importers", "casmech.fmu", "casmech.io.plot",
                            "casmech.io.animate", "casmech.cli.replay_record", "difflib",
                            *COMPILER]) == []


def test_a_compiled_run_from_the_cache_takes_no_lock(tmp_path, monkeypatch, quick_builds):
    """A compiled run whose library is in the cache ($CASMECH_CACHE_DIR given) imports neither
    filelock (a lock is taken to build a missing entry only) nor platformdirs (the folder is
    the one given), nor the modules that write C (backends.generate, backends.split), nor
    the optimal-control section's checks; the run that built the entry did take the lock."""
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path / "cache"))
    model = str(MODELS / "pendulum.yaml")

    def run(out: str) -> set[str]:
        return modules_after(
            "import sys; from casmech import cli; "
            f"code = cli.main(['run', {model!r}, '--t-end', '0.02', '--out', "
            f"{str(tmp_path / out)!r}, '--mode', 'compiled', '--quiet'])"
            "\nassert code == 0, code")

    built = run("first")
    assert {"filelock", "casmech.backends.cache", "casmech.backends.generate"} <= built
    again = run("again")
    assert loaded(again, ["filelock", "platformdirs", "casmech.backends.generate",
                          "casmech.backends.split", "casmech.schema.ocp_terms"]) == []
    assert (tmp_path / "again" / "results.csv").read_bytes() == \
        (tmp_path / "first" / "results.csv").read_bytes()


def test_loading_makes_only_the_classes_the_file_uses():
    """The YAML classes of force elements, of estimation, optimal control and studies, of
    components and instances, events and outputs, geometry other than boxes, joint blocks
    (reactions, limits, friction) and of joint types a file does not name are made when a file
    first has one (spec_base.Deferred), and components are imported by a composed file only:
    loading the double pendulum (two revolute joints, no forces) makes the revolute joint's
    class alone; the bushing mount makes the force elements' classes; the compiler's modules
    import no pydantic."""
    assert loaded(modules_after("import casmech.equations.functions, "
                                "casmech.formulations.joint_system"), ["pydantic"]) == []
    probe = ("import json, sys; from casmech.schema import load_model, spec_joints; "
             "load_model(sys.argv[1]); print(json.dumps([sorted(spec_joints.JOINT_CLASSES), "
             "sorted(m for m in sys.modules if m.startswith('casmech.'))]))")
    made = {}
    for name in ("double_pendulum", "bushing_mount"):
        done = subprocess.run([sys.executable, "-c", probe, str(MODELS / f"{name}.yaml")],
                              capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stderr
        made[name] = json.loads(done.stdout.splitlines()[-1])
    joints, modules = made["double_pendulum"]
    assert joints == ["revolute"]
    assert "casmech.schema.spec" in modules
    assert loaded(set(modules), ["casmech.elements.forces.specs", "casmech.schema.spec_problems",
                                 "casmech.schema.components", "casmech.schema.spec_components",
                                 "casmech.schema.spec_events", "casmech.schema.spec_shapes",
                                 "casmech.schema.spec_joint_blocks"]) == []
    assert "casmech.elements.forces.specs" in made["bushing_mount"][1]
