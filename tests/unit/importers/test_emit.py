"""importers/emit.py: whatever text the source holds, the YAML written reads back as exactly
the data the importer meant, and comments stay comments (issue 16: a simEngine3D comment with
line breaks became live keys)."""

import json

import pytest
import yaml

import casmech
from casmech.importers import import_file
from casmech.importers.emit import Imported, Item, comment_lines, identifier, to_yaml
from casmech.schema.loader import load_document
from tests.helpers.importers import DATA

HOSTILE = [
    "plain", "", " leading and trailing ", "yes", "no", "on", "null", "~", "1:30", "0x10",
    "2001-12-14", "1e3", ".inf", "#not a comment", "a: b", "- item", "[1, 2]", "{a: 1}",
    "&anchor", "*alias", "!!python/object/apply:os.system ['echo']", "!tag", "'single'",
    '"double"', "back\\slash", "tab\there", "line\nbreak\nforces:\n  - {name: evil}",
    "cr\rlf\r\n", "nel\x85ls\u2028ps\u2029end", "nul\x00bell\x07esc\x1b", "\ufeffbom",
    "unicode: é ☃ 🙂", "%YAML 1.1", "---", "...", "? key", "| block", "> folded", "@at", "`tick",
]


def model_with(text: str) -> Imported:
    item = Item({"name": "bar", "type": text, "note": [text, 1.5e-5, 2], "nested": {"k": text}},
                [text, f"before {text} after"])
    return Imported(name=text, description=text, header=[text], parameters=[(
        "p", text, text)], gravity=[0.0, 0.0, -9.81], gravity_comments=[text],
        bodies=[item], joints=[Item({"name": "j", "f": text}, [text])],
        analysis=Item({"type": text}, [text]), trailer=[text, text])


@pytest.mark.parametrize("text", HOSTILE, ids=range(len(HOSTILE)))
def test_every_value_reads_back_and_comments_stay_comments(text):
    model = model_with(text)
    written = to_yaml(model)
    data = yaml.safe_load(written)
    assert set(data) == {"casmech", "name", "description", "parameters", "gravity", "bodies",
                         "joints", "analysis"}
    assert data["description"] == text and data["parameters"] == {"p": text}
    assert data["bodies"] == [model.bodies[0].data] and data["joints"] == [model.joints[0].data]
    assert data["analysis"] == {"type": text} and data["gravity"] == [0.0, 0.0, -9.81]
    assert data["name"] == identifier(text) and identifier(text).isidentifier()
    # casmech's own reader agrees (no YAML 1.1 surprise, no tag, no duplicate key)
    document = load_document(written, "imported.yaml")
    assert document.data["bodies"] == [model.bodies[0].data] and not document.diagnostics


def test_comment_lines_split_at_every_line_break():
    lines = comment_lines(["a\nb\rc\r\nd\x85e\u2028f\u2029g", "x\x00y"], "  ")
    assert lines == ["  # a", "  # b", "  # c", "  # d", "  # e", "  # f", "  # g",
                     "  # x\\x00y"]


def test_simengine_comment_round_trip(tmp_path):
    """The course's model with a hostile comment on the model and on a body imports to the
    same model as without them, the comments kept line by line."""
    sample = json.loads((DATA / "me751_pendulum.mdl").read_text())
    evil = "ok\nforces:\n  - {name: f, type: force, body: pendulum, value: [1e6, 0, 0]}\n#"
    sample["comment"], sample["bodies"][1]["comment"] = evil, "x\r- {name: evil}\u2028gravity: 1"
    path = tmp_path / "me751_pendulum.mdl"
    path.write_text(json.dumps(sample))
    (tmp_path / "me751_pendulum.acf").write_text((DATA / "me751_pendulum.acf").read_text())
    text, _ = import_file(path)
    clean, _ = import_file(DATA / "me751_pendulum.mdl")
    strip = lambda t: [line for line in t.splitlines() if not line.lstrip().startswith("#")]  # noqa: E731
    assert strip(text) == strip(clean)
    assert "# forces:" in text and "#   - {name: f, type: force, body: pendulum, value: [1e6, " \
        "0, 0]}" in text
    model = casmech.loads(text)
    assert model.forces == () and list(model.gravity) == [0.0, 0.0, -9.81]
