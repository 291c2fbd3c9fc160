"""Files a model names (schema/files.py): inside the model's folder or an allowed one, regular
files only, read with a bound; table errors never quote a file's contents."""

import os

import pytest

from casmech.errors import ModelError
from casmech.schema import files, load_model
from casmech.schema.tables import MAX_ROWS
from tests.texts import pendulum

ROWS = "t, angle\n0, 0\n1, 0.1\n2, 0.2\n3, 0.1\n"


def model(folder, table: str):
    folder.mkdir(exist_ok=True)
    path = folder / "m.yaml"
    path.write_text(pendulum(f"{{table: {table}, column: angle}}"))
    return path


def findings(path) -> list:
    with pytest.raises(ModelError) as caught:
        load_model(path)
    return caught.value.diagnostics


def test_a_table_beside_or_below_the_model_is_read(tmp_path):
    (tmp_path / "m").mkdir()
    (tmp_path / "m" / "data").mkdir()
    (tmp_path / "m" / "data" / "p.csv").write_text(ROWS)
    assert len(load_model(model(tmp_path / "m", "data/p.csv")).joints) == 1


@pytest.mark.parametrize("table", ["../p.csv", "/etc/passwd", "/proc/self/environ", "/dev/zero",
                                   "data/../../p.csv"])
def test_paths_outside_the_folder_are_refused_without_reading(tmp_path, table):
    (tmp_path / "p.csv").write_text(ROWS)
    [diagnostic] = findings(model(tmp_path / "m", table))
    assert (diagnostic.code, diagnostic.path) == ("E305", "joints[0].driver.angle.table")
    assert diagnostic.source.line == 12 and "outside the model's folder" in diagnostic.message


def test_a_symbolic_link_out_of_the_folder_is_outside(tmp_path):
    (tmp_path / "p.csv").write_text(ROWS)
    (tmp_path / "m").mkdir()
    (tmp_path / "m" / "link.csv").symlink_to(tmp_path / "p.csv")
    assert [d.code for d in findings(model(tmp_path / "m", "link.csv"))] == ["E305"]


def test_allowed_folders(tmp_path, monkeypatch):
    (tmp_path / "shared").mkdir()
    (tmp_path / "shared" / "p.csv").write_text(ROWS)
    path = model(tmp_path / "m", "../shared/p.csv")
    assert [d.code for d in findings(path)] == ["E305"]
    monkeypatch.setenv(files.ALLOWED_DIRS, str(tmp_path / "shared"))
    assert len(load_model(path).joints) == 1
    monkeypatch.delenv(files.ALLOWED_DIRS)
    monkeypatch.setattr(files, "_extra", [])
    files.allow(tmp_path / "shared")  # what --allow-dir does
    assert len(load_model(path).joints) == 1


def test_only_regular_files(tmp_path):
    folder = tmp_path / "m"
    folder.mkdir()
    os.mkfifo(folder / "pipe.csv")  # opening it would block until someone writes
    (folder / "dir.csv").mkdir()
    for name in ("pipe.csv", "dir.csv"):
        [diagnostic] = findings(model(folder, name))
        assert diagnostic.code == "E305" and "not a regular file" in diagnostic.message


def test_size_and_rows_are_bounded(tmp_path, monkeypatch):
    folder = tmp_path / "m"
    folder.mkdir()
    (folder / "long.csv").write_text("t, angle\n" + "".join(f"{k}, 0\n" for k in range(MAX_ROWS
                                                                                     + 1)))
    assert [d.code for d in findings(model(folder, "long.csv"))] == ["E306"]
    monkeypatch.setattr("casmech.schema.tables.MAX_BYTES", 100)
    (folder / "big.csv").write_text(ROWS * 10)
    assert [d.code for d in findings(model(folder, "big.csv"))] == ["E306"]


def test_table_errors_do_not_quote_the_file(tmp_path):
    """A header that is not column names is not listed; a bad cell is named by position."""
    folder = tmp_path / "m"
    folder.mkdir()
    (folder / "env.csv").write_text("SECRET=hunter2 HOME=/root\n0\n")
    (folder / "row.csv").write_text("t, angle\n0, 0\nhunter2, 1\n")
    for name, words in (("env.csv", "not a header of column names"),
                        ("row.csv", "value 1 of 2 is not a number")):
        [diagnostic] = findings(model(folder, name))
        assert "hunter2" not in diagnostic.format() and words in diagnostic.format()


def test_component_files_inside_the_folder_bounded(tmp_path, monkeypatch):
    folder = tmp_path / "m"
    folder.mkdir()
    (tmp_path / "part.yaml").write_text("bodies: []\n")
    (folder / "big.yaml").write_text("bodies: []\n# " + "x" * 200 + "\n")
    text = "casmech: 1\nname: c\ncomponents:\n  part: {file: FILE}\ninstances:\n" \
           "  - {name: one, component: part}\n"
    monkeypatch.setattr(files, "MAX_MODEL_BYTES", 100)
    for name, code in (("../part.yaml", "E305"), ("/dev/zero", "E305"), ("big.yaml", "E306")):
        (folder / "m.yaml").write_text(text.replace("FILE", name))
        [diagnostic] = findings(folder / "m.yaml")
        assert (diagnostic.code, diagnostic.source.line) == (code, 4)


def test_read_bounded(tmp_path):
    (tmp_path / "f").write_bytes(b"x" * 10)
    assert files.read_bounded(tmp_path / "f", 10) == b"x" * 10
    with pytest.raises(files.TooLarge):
        files.read_bounded(tmp_path / "f", 9)
    with pytest.raises(files.TooLarge):
        files.read_bounded("/dev/zero", 1 << 20)
