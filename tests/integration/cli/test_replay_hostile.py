"""`casmech run --replay` on a metadata.json crafted by someone else (issue 35 items 3 and 14):
it reads only the files the record lists, inside the model's folder or a folder the command
line allows, after their hash check; a record's own allow_dir is refused unless repeated;
malformed records are located errors (exit 2), never tracebacks."""

import hashlib
import json
from pathlib import Path

import pytest

from casmech import cli
from casmech.schema import files
from tests.integration.cli.test_replay import MODEL, PROFILE

PASSWD = Path("/etc/passwd")


def sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.fixture()
def recorded(tmp_path, monkeypatch):
    """A genuine run's folder and its metadata (as a dict), and a record of every file
    casmech hashes from now on."""
    monkeypatch.setattr(files, "_extra", [])
    (tmp_path / "pendulum.yaml").write_text(MODEL)
    (tmp_path / "profile.csv").write_text(PROFILE)
    (tmp_path / "bar.stl").write_text("solid bar\nendsolid bar\n")
    assert cli.main(["run", str(tmp_path / "pendulum.yaml"), "--out", str(tmp_path / "run"),
                     "--mode", "interpreted"]) == 0
    hashed = []
    digest = files.digest

    def recording(path, *args, **kwargs):
        hashed.append(Path(path).resolve())
        return digest(path, *args, **kwargs)

    monkeypatch.setattr(files, "digest", recording)
    record = json.loads((tmp_path / "run" / "metadata.json").read_text())
    return tmp_path, record, hashed


def _replay(folder: Path, record: dict, *extra: str) -> int:
    path = folder / "crafted" / "metadata.json"
    path.parent.mkdir(exist_ok=True)
    path.write_text(json.dumps(record, indent=1))
    return cli.main(["run", "--replay", str(path), "--out", str(folder / "replayed"), *extra])


@pytest.mark.skipif(not PASSWD.is_file(), reason="no /etc/passwd here")
def test_a_listed_file_outside_the_models_folder_is_never_read(recorded, capsys):
    folder, record, hashed = recorded
    record["files"]["passwd"] = {"path": str(PASSWD), "sha256": sha(PASSWD)}
    record["options"]["allow_dir"] = ["/"]
    assert _replay(folder, record) == 2
    err = capsys.readouterr().err
    assert "allow_dir: /)" in err and "add --allow-dir / if you trust it" in err
    del record["options"]["allow_dir"]
    assert _replay(folder, record) == 2
    assert f"{PASSWD}: outside the model's folder and every --allow-dir" in \
        capsys.readouterr().err
    assert PASSWD.resolve() not in hashed
    assert not (folder / "replayed").exists()  # refused before anything was written


def test_a_model_missing_from_the_files_is_refused(recorded, capsys):
    """The reproducer of item 3: `files: {}` and `allow_dir: ["/"]`, the model elsewhere."""
    folder, record, hashed = recorded
    record["files"] = {}
    assert _replay(folder, record, "--allow-dir", str(folder)) == 2
    err = capsys.readouterr().err
    assert "is not among the files it records with their sha256" in err
    assert hashed == [] and not (folder / "replayed").exists()


def test_a_file_the_record_does_not_list_is_refused_before_the_run(recorded, capsys):
    """The model (listed, unchanged) reads a table the record leaves out."""
    folder, record, _ = recorded
    del record["files"]["profile.csv"]
    assert _replay(folder, record) == 2
    assert f"does not list {(folder / 'profile.csv').resolve()}, which the model read" in \
        capsys.readouterr().err
    assert not (folder / "replayed").exists()


def test_a_listed_folder_that_is_not_a_file_is_refused(recorded, capsys):
    folder, record, hashed = recorded
    (folder / "sub").mkdir()
    record["files"]["sub"] = {"path": str(folder / "sub"), "sha256": "0" * 64}
    assert _replay(folder, record) == 2
    assert f"{folder / 'sub'}: not a regular file" in capsys.readouterr().err


def test_the_genuine_record_replays(recorded):
    folder, record, hashed = recorded
    assert _replay(folder, record) == 0
    assert set(hashed) == {(folder / name).resolve()
                           for name in ("pendulum.yaml", "profile.csv", "bar.stl")}


# what is changed in a genuine record -> the path and code reported, and a text of the line
# reported (the value at fault, or the mapping a missing key belongs in)
MALFORMED = {
    "files is a list": (lambda r: r.update(files=[]), "error[E102] files:", '"files": []'),
    "a file without its sha256": (lambda r: r["files"]["bar.stl"].pop("sha256"),
                                  'error[E100] files["bar.stl"].sha256: missing required key',
                                  '"bar.stl": {'),
    "a short sha256": (lambda r: r["files"]["bar.stl"].update(sha256="abc"),
                       'error[E103] files["bar.stl"].sha256', '"sha256": "abc"'),
    "t_end as text": (lambda r: r["analysis"].update(t_end="0.4"),
                      "error[E102] analysis.t_end: Input should be a valid number",
                      '"t_end": "0.4"'),
    "no analysis": (lambda r: r.pop("analysis"), "error[E100] analysis: missing required key",
                    "{"),
    "an unknown mode": (lambda r: r.update(mode="fast"), "error[E103] mode:", '"mode": "fast"'),
    "an unknown format": (lambda r: r["options"].update(format=["xml"]),
                          "error[E103] options.format[0]:", '"xml"'),
    "allow_dir as text": (lambda r: r["options"].update(allow_dir="/"),
                          "error[E102] options.allow_dir:", '"allow_dir": "/"'),
    "an override as a list": (lambda r: r["overrides"].update(m=[1]), "error[E102] overrides:",
                              '"overrides": {'),
    "the model path as a number": (lambda r: r["model"].update(absolute_path=5),
                                   "error[E102] model.absolute_path:", '"absolute_path": 5'),
    "the model as text": (lambda r: r.update(model="x"), "error[E102] model:", '"model": "x"'),
}


@pytest.mark.parametrize("change", MALFORMED)
def test_a_malformed_record_is_a_located_error(recorded, change, capsys):
    folder, record, hashed = recorded
    edit, message, shown = MALFORMED[change]
    edit(record)
    assert _replay(folder, record) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and message in err, err
    crafted = folder / "crafted" / "metadata.json"
    (located,) = [line for line in err.splitlines() if line.startswith(f"{crafted}:")]
    line, col = (int(n) for n in located.split(":")[1:3])
    text = crafted.read_text().splitlines()[line - 1]
    assert shown in text and col <= len(text), (located, text)
    assert hashed == [] and not (folder / "replayed").exists()
