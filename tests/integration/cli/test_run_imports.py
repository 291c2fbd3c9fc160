"""What a warm compiled `casmech run` imports: a run of a tree whose library and model the cache
holds loads its functions compiled and builds no symbolic function, so it imports none of the
modules that build them (docs/decisions/warm-run-imports.md)."""

import json
import os
import subprocess
import sys

from tests.conftest import ROOT

# runs the command line and prints, last on stderr, the modules the process imported (by an
# atexit handler: `casmech run` ends the process as it returns, cli._leave)
PROBE = ("import atexit, json, sys\nfrom casmech.cli import main\n"
         "atexit.register(lambda: print(json.dumps(sorted(sys.modules)), file=sys.stderr))\n"
         "sys.exit(main())")
# the symbolic builders and the other formulations' runs, imported by the functions that use
# them (docs/decisions/warm-run-imports.md)
SYMBOLIC = ("casmech.equations.eom", "casmech.equations.initial_rows",
            "casmech.equations.results_row", "casmech.formulations.joint_control",
            "casmech.formulations.mapped_system", "casmech.runtime.dynamics",
            "casmech.runtime.dae_integrators", "casmech.runtime.dae_rows",
            "casmech.runtime.functional_ode", "casmech.runtime.projected_rk4",
            "casmech.runtime.singular_poses",
            # the builder and its kernels (backends.deferred names the bundle's functions from
            # equations.bundle_names), the DAE residuals' kernels and the joint system's build
            "casmech.equations.system", "casmech.equations.assemble", "casmech.equations.bodies",
            "casmech.equations.body_kernels", "casmech.equations.force_kernels",
            "casmech.equations.force_laws", "casmech.equations.forces", "casmech.equations.inline",
            "casmech.equations.layout", "casmech.equations.row_kernels", "casmech.equations.rows",
            "casmech.formulations.dae", "casmech.formulations.dae_terms",
            "casmech.formulations.residual_groups", "casmech.formulations.residual_kernels",
            "casmech.numerics.element_sums", "casmech.formulations.joint_forces",
            "casmech.formulations.rnea", "casmech.formulations.tree_steps",
            "casmech.formulations.mapped_rows", "casmech.formulations.mapped_tree",
            # what other analyses, formulations and formats use: loops, projections, the
            # prescribed step, parametric libraries, method auto's stiffness, HDF5, DAE options,
            # least squares, DOP853's steps in Python, loads' checks, limits and motors
            "casmech.formulations.augmented", "casmech.formulations.loop_ode",
            "casmech.formulations.prescribed", "casmech.formulations.table",
            "casmech.model.parametric", "casmech.numerics.kkt", "casmech.runtime.joint_rows",
            "casmech.runtime.stiffness", "casmech.io.hdf5", "casmech.io.staged",
            "casmech.formulations.dae_options", "casmech.numerics.numeric_qr",
            "casmech.numerics.sparse_qr", "casmech.numerics.hermite_pair",
            "casmech.runtime.load_checks", "casmech.equations.limits", "casmech.equations.motors")


# two bars hanging from spherical joints, no parameters (a parametric model's results row is
# built over its bound library: equations.results_row)
CHAIN = ROOT / "benchmarks" / "models" / "chain2.yaml"


def _modules(tmp_path, *args) -> set[str]:
    model = tmp_path / "chain2.yaml"
    model.write_bytes(CHAIN.read_bytes())
    env = {**os.environ, "CASMECH_CACHE_DIR": str(tmp_path / "cache")}
    done = subprocess.run([sys.executable, "-c", PROBE, "run", str(model), "--t-end", "0.1",
                           "--out", str(tmp_path / "out"), *args], env=env, capture_output=True,
                          text=True, timeout=300, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    return set(json.loads(done.stderr.splitlines()[-1]))


def test_a_warm_compiled_run_imports_no_symbolic_builder(tmp_path):
    built = _modules(tmp_path, "--mode", "compiled")  # builds the library: every builder
    assert [m for m in SYMBOLIC if m in built] != []
    warm = _modules(tmp_path)
    assert "casmech.backends.load" in warm  # the run loaded its library
    assert [m for m in SYMBOLIC if m in warm] == []
