"""The FMU's reaction columns in the frames and about the points the joints' `reactions:`
name, as `casmech run` writes them (runtime.reaction_frames, computed apart from the FMU's C)."""

import casmech
from tests.helpers.fmu import MODELS, assert_matches, build, reference, simulate

FRAMES = {"pivot": "{frame: body_j}", "elbow": "{frame: joint, point: [0, 0.1, -1.2]}"}


def test_reactions_in_their_frames(toolchain, tmp_path):
    text = (MODELS / "double_pendulum.yaml").read_text()
    for joint, reactions in FRAMES.items():
        head = f"  - name: {joint}\n    type: revolute\n"
        assert head in text
        text = text.replace(head, head + f"    reactions: {reactions}\n")
    model = casmech.loads(text, str(MODELS / "double_pendulum_frames.yaml"))
    fmu = build(model, tmp_path, toolchain, "frames", outputs=("pivot.*", "elbow.*"))
    expected = reference(model)
    got = simulate(fmu, "CoSimulation")
    assert sorted(got) == sorted(f"{j}.{c}" for j in FRAMES for c in
                                 ("fx", "fy", "fz", "tx", "ty", "tz"))
    assert_matches(got, expected)
    plain = reference(casmech.load(MODELS / "double_pendulum.yaml"))
    assert abs(plain["elbow.tx"] - expected["elbow.tx"]) > 1e-3  # the frames matter here
