"""The IFToMM A02 N-four-bar for any N, written out like
models/validation/iftomm_a02_four_bar_N2.yaml (whose comments explain the joints: revolutes to
ground, then a universal at each coupler's left end and a spherical at its right end, so the
constraint Jacobian has full row rank)."""

from pathlib import Path

N2_MODEL = Path(__file__).parents[2] / "models" / "validation" / "iftomm_a02_four_bar_N2.yaml"


def a02_model(n: int) -> str:
    text = N2_MODEL.read_text()
    head = text[:text.index("bodies:")].replace("N2", f"N{n}").replace("N = 2", f"N = {n}")
    analysis = text[text.index("analysis:"):]
    bodies = [f"  - {{name: crank{i}, mass: m, inertia: [It, Ia, It], position: [{i}*L, L/2, 0],"
              f" velocity: [-w * L/2, 0, 0], angular_velocity: [0, 0, w]}}" for i in range(n + 1)]
    bodies += [f"  - {{name: coupler{i}, mass: m, inertia: [Ia, It, It], "
               f"position: [{i}*L + L/2, L, 0], velocity: [-w * L, 0, 0]}}" for i in range(n)]
    joints = [f"  - {{name: ground{i}, type: revolute, body_i: ground, body_j: crank{i}, "
              f"at: [{i}*L, 0, 0], axis: [0, 0, 1]}}" for i in range(n + 1)]
    for i in range(n):
        joints.append(f"  - {{name: u{i}, type: universal, body_i: crank{i}, body_j: coupler{i},"
                      f" at: [{i}*L, L, 0], axis_i: [0, 0, 1], axis_j: [0, 1, 0]}}")
        joints.append(f"  - {{name: s{i}, type: spherical, body_i: crank{i + 1}, "
                      f"body_j: coupler{i}, at: [{i + 1}*L, L, 0]}}")
    return "\n".join([head + "bodies:", *bodies, "", "joints:", *joints, "", analysis])
