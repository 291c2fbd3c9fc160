"""YAML loading: plain data, source map, duplicate keys, fatal errors."""

import pytest

from casmech.errors import ModelError, Source, UsageError
from casmech.schema import loader
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


# ------------------------------------------------------------------ YAML 1.1, tags, limits
@pytest.mark.parametrize("text", ["1:30", "0x10", "010", "0b101", "1_000", "1:30.5", "yes", "No",
                                  "on", "OFF", "2001-12-14", "2001-12-14 21:59:43.10 -5"])
def test_yaml_11_spellings_are_reported_not_converted(text):
    """YAML 1.1 (PyYAML) reads these as 90, 16, 8, 5, 1000, 90.5, booleans and dates; YAML
    1.2 as text. Neither is what a model means: E004 at the value."""
    with pytest.raises(ModelError) as caught:
        load_document(f"a: 1\nb: [2, {text}]\n", "s.yaml")
    [diagnostic] = caught.value.diagnostics
    assert (diagnostic.code, diagnostic.path, diagnostic.source) == \
        ("E004", "b[1]", Source("s.yaml", 2, 8))


@pytest.mark.parametrize("text, value", [("12", 12), ("-0", 0), ("+3", 3), ("1.5", 1.5),
                                         ("-2.5e+3", -2500.0), (".inf", float("inf")),
                                         ("true", True), ("FALSE", False), ("~", None),
                                         ("1e-3", "1e-3"), ("'1:30'", "1:30"),
                                         ("!!str 0x10", "0x10"), ("'yes'", "yes")])
def test_yaml_12_values(text, value):
    assert load_document(f"a: {text}\n").data["a"] == value


@pytest.mark.parametrize("text", ["!!python/object/apply:os.system [echo]", "!custom 1",
                                  "!!binary aGVsbG8=", "!!set {a, b}", "!!timestamp 2001-12-14",
                                  "!!python/name:os.system"])
def test_tags_are_refused(text):
    with pytest.raises(ModelError) as caught:
        load_document(f"a: 1\nb: {text}\n", "s.yaml")
    [diagnostic] = caught.value.diagnostics
    assert (diagnostic.code, diagnostic.source) == ("E005", Source("s.yaml", 2, 4))


def test_aliases_are_located_at_their_anchor():
    document = load_document("a: &x {b: [1, 2]}\nc: *x\n", "s.yaml")
    assert document.data["c"] == {"b": [1, 2]}
    assert document.locate(("c", "b", 1)) == Source("s.yaml", 1, 15)


def test_aliases_of_aliases_are_located_at_the_innermost_anchor():
    """Every value an alias repeats, through an alias inside an anchored value, is located
    where it is written, and each key at its key."""
    text = ("a: &x {b: [1, 2], c: 3}\n"
            "d: &y {e: *x, f: [*x, 4]}\n"
            "g: [*y, *y]\n")
    document = load_document(text, "s.yaml")
    assert document.data["g"][1]["f"][0] == {"b": [1, 2], "c": 3}
    at = {("a", "b", 1): (1, 15), ("a", "c"): (1, 22)}  # where each value of x is written
    for path, (line, col) in at.items():
        tail = path[1:]
        for prefix in [("a",), ("d", "e"), ("d", "f", 0), ("g", 0, "e"), ("g", 1, "f", 0)]:
            assert document.locate((*prefix, *tail)) == Source("s.yaml", line, col), prefix
    assert document.locate(("g", 1, "f", 1)) == Source("s.yaml", 2, 23)
    assert document.source_map.keys[("g", 0, "e", "c")] == Source("s.yaml", 1, 19)


def test_alias_expansion_is_bounded():
    """A 'billion laughs' (9 levels of 8 aliases: 8^9 values) stops at MAX_VALUES."""
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x]"]
    lines += [f"a{k}: &a{k} [" + ", ".join([f"*a{k - 1}"] * 8) + "]" for k in range(1, 9)]
    with pytest.raises(ModelError) as caught:
        load_document("\n".join(lines) + "\n", "s.yaml")
    [diagnostic] = caught.value.diagnostics
    assert diagnostic.code == "E006" and f"more than {loader.MAX_VALUES} values" in \
        diagnostic.message


def test_nesting_is_bounded_without_recursion():
    depth = 100_000  # far beyond Python's recursion limit
    with pytest.raises(ModelError) as caught:
        load_document("a: " + "[" * depth + "]" * depth + "\n", "s.yaml")
    [diagnostic] = caught.value.diagnostics
    assert diagnostic.code == "E006" and diagnostic.source.col == 3 + loader.MAX_DEPTH


def test_file_size_is_bounded(tmp_path):
    path = tmp_path / "big.yaml"
    path.write_text("a: 1\n# " + "x" * loader.MAX_MODEL_BYTES + "\n")
    for source in (path, "/dev/zero"):
        with pytest.raises(ModelError) as caught:
            load_file(str(source))
        assert caught.value.diagnostics[0].code == "E006"
    with pytest.raises(ModelError):
        load_document(path.read_text(), "big.yaml")
