"""YAML loading: plain data, source map, duplicate keys, fatal errors."""

import pytest

from casmech.errors import ModelError, Source, UsageError
from casmech.schema.loader import format_path, load_document, load_file

TEXT = """\
casmech: 1
name: demo
parameters:
  small: 1e-3
  big: 2.0E+3
  on: 4
bodies:
  - name: bar
    mass: "2 * m"
    inertia: ['a +  b', 1, 1]
    position: [0, 0, 0]
    ok: true
    nothing: null
    note: |
      two
      lines
    escaped: "a\\tb + c"
"""


@pytest.fixture(scope="module")
def document():
    return load_document(TEXT, "demo.yaml")


def test_plain_data(document):
    assert document.data["casmech"] == 1
    assert document.data["parameters"] == {"small": "1e-3", "big": 2000.0, "on": 4}
    body = document.data["bodies"][0]
    assert body["inertia"] == ["a +  b", 1, 1]
    assert (body["ok"], body["nothing"]) == (True, None)
    assert body["note"] == "two\nlines\n"


def test_values_and_keys_are_located(document):
    assert document.locate(()) == Source("demo.yaml", 1, 1)
    assert document.locate(("parameters", "big")) == Source("demo.yaml", 5, 8)
    assert document.locate(("bodies", 0)) == Source("demo.yaml", 8, 5)
    assert document.locate(("bodies", 0, "inertia", 1)) == Source("demo.yaml", 10, 25)
    assert document.locate_key(("bodies", 0, "mass")) == Source("demo.yaml", 9, 5)


def test_unknown_paths_walk_up_to_the_nearest_ancestor(document):
    assert document.locate(("bodies", 0, "inertia", 7, "x")) == Source("demo.yaml", 10, 14)
    assert document.locate(("nowhere",)) == Source("demo.yaml", 1, 1)
    assert document.locate_key(("bodies", 0, "velocity")) == Source("demo.yaml", 8, 5)


@pytest.mark.parametrize(
    ("path", "offset", "expected"),
    [
        (("bodies", 0, "mass"), 4, (9, 16)),  # double-quoted: one column for the quote
        (("bodies", 0, "inertia", 0), 5, (10, 21)),  # single-quoted, flow sequence
        (("bodies", 0, "name"), 2, (8, 13)),  # plain
        (("parameters", "small"), 1, (4, 11)),  # a string YAML did not take for a number
        (("bodies", 0, "note"), 4, (14, 11)),  # block scalar: the scalar's start
        (("bodies", 0, "escaped"), 6, (17, 14)),  # escapes shift columns: the scalar's start
    ],
)
def test_columns_inside_scalars(document, path, offset, expected):
    assert document.source_in_scalar(path, offset) == Source("demo.yaml", *expected)


def test_duplicate_keys_are_reported_and_the_first_kept():
    document = load_document("a: 1\nb:\n  c: 2\n  c: 3\na: 4\n", "d.yaml")
    assert document.data == {"a": 1, "b": {"c": 2}}
    found = [(d.code, d.path, d.source.line, d.source.col) for d in document.diagnostics]
    assert found == [("E002", "b.c", 4, 3), ("E002", "a", 5, 1)]
    assert "first at line 1" in document.diagnostics[1].message


@pytest.mark.parametrize(
    ("text", "line", "col"),
    [
        ("a: [1, 2\nb: 3\n", 2, 2),
        ("a: 1\n\tb: 2\n", 2, 1),
        ("a: 'open\n", 2, 1),
        ("a: 1\n---\nb: 2\n", 2, 1),
        ("a: \x07\n", 1, 4),
    ],
)
def test_yaml_syntax_errors(text, line, col):
    with pytest.raises(ModelError) as caught:
        load_document(text, "s.yaml")
    [diagnostic] = caught.value.diagnostics
    assert (diagnostic.code, diagnostic.source) == ("E001", Source("s.yaml", line, col))


@pytest.mark.parametrize(
    ("text", "got"), [("", "an empty document"), ("- a\n", "a list"), ("42\n", "a scalar")]
)
def test_top_level_must_be_a_mapping(text, got):
    with pytest.raises(ModelError) as caught:
        load_document(text, "t.yaml")
    [diagnostic] = caught.value.diagnostics
    assert (diagnostic.code, diagnostic.got) == ("E003", got)


def test_non_scalar_key():
    document = load_document("? [a, b]\n: 1\nc: 2\n")
    assert document.data == {"c": 2}
    assert [d.code for d in document.diagnostics] == ["E102"]


def test_files(tmp_path):
    path = tmp_path / "model.yaml"
    path.write_text("a: 1\n", encoding="utf-8")
    assert load_file(str(path)).file == str(path)
    with pytest.raises(UsageError, match="no such file"):
        load_file(str(tmp_path / "missing.yaml"))
    with pytest.raises(UsageError, match="cannot read model file"):
        load_file(str(tmp_path))  # a directory
    path.write_bytes(b"a: \xff\xfe\n")
    with pytest.raises(ModelError) as caught:
        load_file(str(path))
    assert caught.value.diagnostics[0].code == "E001"


def test_format_path():
    assert format_path(("joints", 0, "driver", "angle")) == "joints[0].driver.angle"
    assert format_path(("bodies", 1, "inertia", 2, 0)) == "bodies[1].inertia[2][0]"
    assert format_path(()) == ""
