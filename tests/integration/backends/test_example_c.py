"""examples/c/evaluate_phi.c, built with the plain gcc line of its README against the library
`casmech compile` wrote, prints Phi and Phi_q equal to the Python (interpreted) functions."""

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import ROOT

EXAMPLE = ROOT / "examples" / "c" / "evaluate_phi.c"


@pytest.fixture(scope="module")
def program(build_dir, tmp_path_factory) -> Path:
    if shutil.which("gcc") is None:
        pytest.skip("no gcc")
    binary = tmp_path_factory.mktemp("example") / "evaluate_phi"
    subprocess.run(["gcc", "-std=c99", "-Wall", "-Werror", f"-I{build_dir}", str(EXAMPLE),
                    f"-L{build_dir}", "-lcasmech_model", f"-Wl,-rpath,{build_dir}",
                    "-o", str(binary)], check=True, capture_output=True)
    return binary


def _parse(text: str, n_rows: int, n_q: int) -> tuple[np.ndarray, np.ndarray, set]:
    phi, phi_q, pattern = np.full(n_rows, np.nan), np.zeros((n_rows, n_q)), set()
    for line in text.splitlines():
        kind, *fields = line.split()
        if kind == "phi":
            phi[int(fields[0])] = float(fields[1])
        else:
            i, j = int(fields[0]), int(fields[1])
            phi_q[i, j] = float(fields[2])
            pattern.add((i, j))
    return phi, phi_q, pattern


@pytest.mark.parametrize("seed", [0, 1])
def test_example_prints_the_python_values(program, interpreted, seed):
    rng = np.random.default_rng(seed)
    t, q = rng.uniform(0, 2), rng.uniform(-1, 1, interpreted.n_coordinates)
    arguments = [format(value, ".17g") for value in (t, *q)]  # exact doubles
    done = subprocess.run([str(program), *arguments], capture_output=True, text=True, check=True)
    phi, phi_q, pattern = _parse(done.stdout, interpreted.n_rows, interpreted.n_coordinates)
    # printed with 17 significant digits: exact round trip of the doubles, same operations
    np.testing.assert_allclose(phi, interpreted.vector("phi", t, q), rtol=1e-15, atol=1e-15)
    np.testing.assert_allclose(phi_q, interpreted.matrix("phi_q", t, q), rtol=1e-15, atol=1e-15)
    sparsity = interpreted["phi_q"].sparsity_out(0)
    assert pattern == set(zip(*sparsity.get_triplet(), strict=True))


def test_example_rejects_a_wrong_number_of_coordinates(program):
    done = subprocess.run([str(program), "0.0", "1.0"], capture_output=True, text=True)
    assert done.returncode == 2 and "expected 14 coordinates" in done.stderr
