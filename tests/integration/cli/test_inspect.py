"""casmech inspect against hand counts: the four-bar's rows per joint (revolute 5 + driver 1,
spherical 3, universal 4, revolute 5, one normalization per body), their YAML lines found in the
file text, q indices from q = [r_1..r_nb, p_1..p_nb]; a pendulum with a second revolute on the
same axis point has exactly that joint's 5 rows redundant."""

import re

from casmech import cli
from tests.conftest import MODELS

FOUR_BAR = MODELS / "four_bar.yaml"
HAND_COUNT = {"crank_pivot": 6, "coupler_pin": 3, "rocker_pin": 4, "rocker_pivot": 5}


def inspect(path, capsys):
    assert cli.main(["inspect", str(path)]) == 0
    return capsys.readouterr().out


def groups(out):
    """heading name -> list of row lines under it."""
    found, current = {}, None
    for line in out.splitlines():
        heading = re.match(r"  (?:joint '(\w+)'|(normalization)) .*: (\d+) rows$", line)
        if heading:
            current = heading.group(1) or heading.group(2)
            found[current] = []
        elif current and re.match(r"    \[\s*\d+\]", line):
            found[current].append(line)
        else:
            current = None
    return found


def line_of(path, text):
    return 1 + path.read_text().splitlines().index(text)


def test_four_bar_rows_by_joint(capsys):
    out = inspect(FOUR_BAR, capsys)
    rows = groups(out)
    assert {name: len(lines) for name, lines in rows.items()} == {**HAND_COUNT,
                                                                   "normalization": 3}
    indices = [int(re.search(r"\[\s*(\d+)\]", line).group(1))
               for lines in rows.values() for line in lines]
    assert indices == list(range(21))  # phi's rows in order, each once
    for joint in HAND_COUNT:
        line = line_of(FOUR_BAR, f"  - name: {joint}")
        assert all(f"four_bar.yaml:{line}:" in row for row in rows[joint]
                   if "rotation angle" not in row)
    driver = [row for row in rows["crank_pivot"] if "rotation angle" in row]
    assert len(driver) == 1 and f"four_bar.yaml:{line_of(FOUR_BAR, '    driver:')}:" in driver[0]
    assert [row.split()[2] for row in rows["rocker_pin"]] == ["cd", "cd", "cd", "dp1"]
    assert "REDUNDANT" not in out
    # 3 bodies x 7 coordinates, 21 independent rows: rank 21, DOF 0 (fully driven)
    assert "coordinates: 21 " in out and "rank: 21" in out and "degrees of freedom: 0" in out


def test_four_bar_coordinate_indices(capsys):
    out = inspect(FOUR_BAR, capsys)
    for k, body in enumerate(("crank", "coupler", "rocker")):
        line = next(text for text in out.splitlines() if text.startswith(f"  {body} "))
        assert f"q[{3 * k}:{3 * k + 3}]" in line and f"q[{9 + 4 * k}:{13 + 4 * k}]" in line
        assert f"four_bar.yaml:{line_of(FOUR_BAR, f'  - name: {body}')}:" in line


def test_redundant_joint_rows_are_marked(tmp_path, capsys):
    model = tmp_path / "redundant.yaml"
    extra = ("  - name: second_pivot\n    type: revolute\n    body_i: ground\n    body_j: bar\n"
             "    at: [0, 0, 0]\n    axis: [1, 0, 0]\n")
    model.write_text((MODELS / "me751_pendulum.yaml").read_text()
                     .replace("\nanalysis:", extra + "\nanalysis:"))
    out = inspect(model, capsys)
    rows = groups(out)
    # the second revolute repeats the first one's 5 rows; the first keeps its 5 + driver
    assert len(rows["second_pivot"]) == 5
    assert all(row.endswith("REDUNDANT") for row in rows["second_pivot"])
    assert out.count("REDUNDANT") == 5
    line = line_of(model, "  - name: second_pivot")
    assert all(f"redundant.yaml:{line}:" in row for row in rows["second_pivot"])
    # 1 body: 7 coordinates; 6 + 5 + 1 = 12 rows of rank 7; DOF 7 - 7 = 0
    assert "constraint rows: 12" in out and "rank: 7" in out and "degrees of freedom: 0" in out


def test_missing_model_exit_2(tmp_path, capsys):
    assert cli.main(["inspect", str(tmp_path / "none.yaml")]) == 2
    assert "no such file" in capsys.readouterr().err
