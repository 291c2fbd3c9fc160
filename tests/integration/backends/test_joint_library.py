"""A compiled joint tree's library (runtime.joint_dynamics.keyed_system, what goes in it:
backends.joint_library) where the user chose no flags: the ODE's forward derivative
fwd1_joint_ode (method auto's probe) compiled at -O0, the results rows at
joint_library.ROWS_FLAGS and the rest at the default flags, all but fwd1_joint_ode with the
machine's instruction set (build.machine_flags, part of the key), large results rows as a chain of
parts (backends.split), all equal to the interpreted system's, the
parts evaluated over rows in C (backends.rows_loop); BDF's
Jacobian from a library of its own, built by the first BDF run, so a BDF run after an Adams
run from one cache is a BDF run from a fresh one; with flags chosen ($CASMECH_CFLAGS) every
function is built with them, under another key."""

import numpy as np

import casmech
from casmech.backends import (
    build,
    cache,
    codegen,
    joint_library,
    manifest,
    rk_library,
    rows_loop,
)
from casmech.runtime.joint_dynamics import joint_system
from casmech.runtime.workspace import Workspace
from tests.integration.backends.test_joint import (
    _assert_jacobian_is_the_odes,
    _assert_same_tree_functions,
)

# a stand-in for the machine's instruction set that every compiler accepts
MACHINE = ("-DCASMECH_MACHINE_FLAGS",)


def _compiles(commands: list, entry) -> dict[str, list[str]]:
    """C source -> the flags gcc compiled it with."""
    return {command[command.index("-c") + 1]: command[1:command.index("-c")]
            for command in commands if "-c" in command
            and (entry / command[command.index("-c") + 1]).is_file()}


def test_seldom_functions_build_quickly_and_large_rows_in_parts(
        model, toolchain, cache_root, interpreted, tmp_path, monkeypatch):
    bundle = codegen.compiled(model, toolchain, root=cache_root, parametric_library=False)
    monkeypatch.delenv(build.FLAGS_ENVIRONMENT)  # no flags chosen
    monkeypatch.setattr(joint_library, "machine_flags", lambda: MACHINE)
    # this small tree's rows too, in three parts
    monkeypatch.setattr(joint_library, "WHOLE_INSTRUCTIONS", 0)
    monkeypatch.setattr(joint_library, "PART_INSTRUCTIONS",
                        -(-joint_system(interpreted).motion.n_instructions() // 3))
    rk_library.rows_driver()  # the rows' C loop (once a process) not among these entries
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path / "first"))
    commands = []
    original = build._run
    monkeypatch.setattr(build, "_run", lambda command, cwd: commands.append(command)
                        or original(command, cwd))
    space = Workspace(bundle)
    fast, slow = joint_system(bundle, workspace=space), joint_system(interpreted)

    (entry,) = cache.entries(tmp_path / "first")
    record = manifest.read(entry)
    names = {function["name"] for function in record["functions"]}
    assert {"joint_ode", "fwd1_joint_ode", *joint_library.motion_parts(3)} <= names
    assert "joint_motion" not in names and record["function_flags"] == {
        "fwd1_joint_ode": ["-O0"],
        **{part: list(joint_library.ROWS_FLAGS + MACHINE)
           for part in joint_library.motion_parts(3)}}
    compiles = _compiles(commands, entry)
    assert len(compiles) >= 3
    for source, flags in compiles.items():
        text = (entry / source).read_text()
        want = ("-O0" if "int fwd1_joint_ode(" in text else joint_library.ROWS_FLAGS[0]
                if "int joint_motion_part" in text else build.DEFAULT_FLAGS[0])
        assert want in flags, (source, flags)
        assert (MACHINE[0] in flags) == (want != "-O0"), (source, flags)
    _assert_same_tree_functions(fast, slow, interpreted.n_bodies)
    call = rows_loop.rows_call(fast.motion)  # the parts in turn over rows, in one C call
    assert call is not None and len(call.entries) == 3
    rng = np.random.default_rng(5)
    times, states = rng.uniform(0, 2, 9), rng.uniform(-0.5, 0.5, (9, fast.layout.n_x))
    signs = np.ones(interpreted.n_bodies)
    want = fast.motion.map(9)(times[None, :], states.T, np.zeros((0, 9)), signs[:, None])
    for got, expected in zip(call(9, times, states, None, signs), want, strict=True):
        # the same compiled parts on the same numbers, through CasADi or the C loop
        np.testing.assert_array_equal(got, np.array(expected).T)

    def run(method: str, workspace: Workspace):
        return casmech.analyze(bundle, "dynamics", formulation="joint", t_end=0.3,
                               method=method, workspace=workspace)

    run("adams", space)
    assert len(cache.entries(tmp_path / "first")) == 1  # Adams compiles no BDF Jacobian
    after = run("bdf", space)
    bdf = [manifest.read(path) for path in cache.entries(tmp_path / "first")]
    assert len(bdf) == 2 and {"joint_ode", "fwd1_joint_ode"} in [
        {function["name"] for function in record["functions"]} for record in bdf]
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path / "fresh"))
    fresh = run("bdf", Workspace(bundle))
    assert after.metadata["method"] == fresh.metadata["method"] == "bdf"
    for name in ("q", "q_dot", "q_ddot", "lam"):
        # the same libraries' C, built twice: the same computation
        np.testing.assert_array_equal(getattr(after, name), getattr(fresh, name))
    _assert_jacobian_is_the_odes(fast, slow)  # BDF's, at the default flags
    # the same library with the flags chosen: the default's own value, all at it, another key
    before = set(cache.entries(tmp_path / "fresh"))
    monkeypatch.setenv(build.FLAGS_ENVIRONMENT, " ".join(build.DEFAULT_FLAGS))
    joint_system(bundle, workspace=Workspace(bundle))
    (chosen,) = set(cache.entries(tmp_path / "fresh")) - before
    assert manifest.read(chosen)["function_flags"] == {}
    # a machine without the instruction set: its own library, under another key
    monkeypatch.delenv(build.FLAGS_ENVIRONMENT)
    monkeypatch.setattr(joint_library, "machine_flags", lambda: ())
    before = set(cache.entries(tmp_path / "fresh"))
    joint_system(bundle, workspace=Workspace(bundle))
    (plain,) = set(cache.entries(tmp_path / "fresh")) - before
    assert MACHINE[0] not in str(manifest.read(plain))
