"""backends/tree_kernels.py: the mapped tree's kernels compiled once per joint type into the
compiled-model cache. The externals equal the SX kernels in value and forward derivative, a
second process's call builds nothing (one entry per joint type, whatever the model), a damaged
library is built again, one others could have written is refused, and then, as without a C
compiler, there are no kernels (runtime.joint_dynamics builds the tree unrolled)."""

import casadi as ca
import numpy as np
import pytest

from casmech.backends import build, cache, library, tree_kernels
from casmech.backends.build import LIBRARY
from casmech.formulations import mapped_rows, mapped_tree
from tests.helpers.codegen import counted_builds

RNG = np.random.default_rng(7)


@pytest.fixture
def builds(monkeypatch) -> list:
    return counted_builds(monkeypatch, library)


def _inputs(function: ca.Function) -> list[np.ndarray]:
    return [RNG.uniform(-1, 1, function.sparsity_in(k).shape) for k in range(function.n_in())]


def test_compiled_kernels_equal_the_sx_ones_and_build_once(toolchain, tmp_path, builds):
    root = tmp_path / "cache"
    kernels = tree_kernels.kernels(["spherical", "revolute"], root, toolchain)
    # one library per joint type, and one of the kernels every tree calls
    assert len(builds) == 3 and len(cache.entries(root)) == 3
    for kind in ("spherical", "revolute", None):
        made = mapped_rows.common() if kind is None else \
            mapped_tree.kernels(kind) | mapped_rows.kernels(kind)
        for name, sx in made.items():
            compiled = kernels[name]
            assert compiled.class_name() == "External"
            args = _inputs(sx)
            for a, b in zip(compiled.call(args), sx.call(args), strict=True):
                # the same operations in C: roundoff
                np.testing.assert_allclose(np.array(a), np.array(b), rtol=1e-12, atol=1e-12)
        if kind is None:
            continue
        down = kernels[mapped_tree.kernel_name(kind, "down")]
        sx = mapped_tree.kernels(kind)[down.name()]
        args, seeds = _inputs(sx), _inputs(sx)
        # the forward derivative from the library (fwd1_<name>) against CasADi's AD of the SX
        fast = down.forward(1).call([*args, *sx.call(args), *seeds])
        slow = sx.forward(1).call([*args, *sx.call(args), *seeds])
        assert "fwd1_" + down.name() in str(down.forward(1))
        for a, b in zip(fast, slow, strict=True):
            np.testing.assert_allclose(np.array(a), np.array(b), rtol=1e-12, atol=1e-12)
    again = tree_kernels.kernels(["revolute"], root, toolchain)
    assert len(builds) == 3 and again.keys() <= kernels.keys()  # the cached libraries


def test_a_damaged_library_is_rebuilt_and_a_foreign_one_refused(toolchain, tmp_path, builds):
    root = tmp_path / "cache"
    tree_kernels.kernels(["revolute"], root, toolchain)
    entry = cache.entries(root)[0]
    data = (entry / LIBRARY).read_bytes()
    (entry / LIBRARY).write_bytes(data[:len(data) // 2])
    with pytest.warns(UserWarning, match="is damaged"):
        tree_kernels.kernels(["revolute"], root, toolchain)
    assert len(builds) == 3
    (entry / LIBRARY).chmod(0o775)  # writable by others: never loaded, nor built over
    with pytest.warns(UserWarning, match="writable by its group.*built unrolled"):
        assert tree_kernels.kernels(["revolute"], root, toolchain) == {}
    assert len(builds) == 3


def test_a_trees_rows_functions_compile_under_their_content(toolchain, tmp_path, builds):
    """The rows Functions of a tree's joints (joint_system.rows_template), by content: the
    same structure in two models is one library; the compiled ones equal the SX ones."""
    import casmech
    from casmech.formulations.tree import spanning_tree
    from tests.unit.formulations.test_mapped_tree import BRANCHED, spherical_chain

    root = tmp_path / "cache"
    for text in (spherical_chain(3), spherical_chain(5), BRANCHED):
        ir = casmech.compile(casmech.loads(text)).ir
        tree = spanning_tree(ir)
        found = tree_kernels.for_tree(ir, tree, root, toolchain)
        for name, sx in mapped_rows.templates(ir, tree).items():
            args = _inputs(sx)
            for a, b in zip(found[name].call(args), sx.call(args), strict=True):
                # the same operations in C: roundoff
                np.testing.assert_allclose(np.array(a), np.array(b), rtol=1e-12, atol=1e-12)
    # chain3: spherical, common and its rows; chain5 nothing; the branched tree: revolute,
    # translational and its two rows Functions in one library
    assert len(builds) == 6


def test_without_a_compiler_there_are_no_kernels(tmp_path):
    missing = build.Toolchain(compiler="no-such-compiler-cc")
    with pytest.warns(UserWarning, match="no C compiler 'no-such-compiler-cc'"):
        assert tree_kernels.kernels(["revolute"], tmp_path / "cache", missing) == {}
    assert not (tmp_path / "cache").exists()
