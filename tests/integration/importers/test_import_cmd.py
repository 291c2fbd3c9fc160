"""`casmech import` on the command line: exit codes, files written, messages."""

import casmech
from casmech.cli import main
from tests.helpers.importers import DATA, DECKS
from tests.unit.importers.test_adm_errors import GOOD


def test_import_writes_a_model_casmech_loads(tmp_path, capsys):
    deck = DECKS / "test_Revolute_Case01.adm"
    out = tmp_path / "models" / "revolute.yaml"
    assert main(["import", str(deck), "-o", str(out)]) == 0
    model = casmech.load(out)
    assert [b.name for b in model.bodies] == ["part_02"]
    captured = capsys.readouterr()
    assert f"{deck} -> {out}: 1 bodies, 1 joints, 0 forces" in captured.out
    # GRAPHICS/0101 of the deck (line 29) is not translated
    assert f"{deck}:29:1: warning[E101] GRAPHICS/0101:" in captured.err


def test_quiet_and_default_output(tmp_path, capsys):
    source = tmp_path / "me751_pendulum.mdl"
    source.write_text((DATA / "me751_pendulum.mdl").read_text())
    assert main(["import", str(source), "--quiet"]) == 0
    assert casmech.load(tmp_path / "me751_pendulum.yaml").joints[5].name == "driver"
    assert capsys.readouterr().err == ""


def test_bad_deck_exits_1_with_located_error(tmp_path, capsys):
    deck = tmp_path / "bad.adm"
    deck.write_text(GOOD.replace("J = 202", "J = 299"))
    assert main(["import", str(deck), "-o", str(tmp_path / "bad.yaml")]) == 1
    assert f"{deck}:9:16: error[E300]" in capsys.readouterr().err
    assert not (tmp_path / "bad.yaml").exists()


def test_translated_model_that_fails_validation_is_written_and_exits_1(tmp_path, capsys):
    deck = tmp_path / "massless.adm"
    deck.write_text(GOOD.replace("MASS = 1", "MASS = 0"))
    out = tmp_path / "massless.yaml"
    assert main(["import", str(deck), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert f"{out}:" in err and "error[E400]" in err and "does not validate" in err
    assert out.exists()


def test_usage_errors_exit_2(tmp_path, capsys):
    other = tmp_path / "model.step"
    other.write_text("")
    assert main(["import", str(other)]) == 2
    assert "expected one of .adm, .mdl, .acf" in capsys.readouterr().err
    assert main(["import", str(tmp_path / "missing.adm")]) == 2
    deck = tmp_path / "same.adm"
    deck.write_text(GOOD)
    assert main(["import", str(deck), "-o", str(deck)]) == 2


def test_sources_are_read_with_a_bound(tmp_path, capsys, monkeypatch):
    """A huge deck is refused by its size (E006), not read whole; an .acf cannot name a model
    file outside its folder (E305)."""
    import casmech.importers

    monkeypatch.setattr(casmech.importers.source, "MAX_SOURCE_BYTES", 1000)
    (tmp_path / "big.adm").write_text("ADAMS\n!" + "x" * 2000 + "\n")
    assert main(["import", str(tmp_path / "big.adm"), "-o", str(tmp_path / "x.yaml")]) == 1
    assert f"{tmp_path / 'big.adm'}:1:1: error[E006]" in capsys.readouterr().err
    (tmp_path / "evil.acf").write_text('{"model": "../../etc/passwd"}')
    assert main(["import", str(tmp_path / "evil.acf"), "-o", str(tmp_path / "x.yaml")]) == 1
    assert "error[E305] model: model file '../../etc/passwd'" in capsys.readouterr().err
