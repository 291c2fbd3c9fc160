"""docs/api.md: every `python` block runs, in order, in one namespace, from a temporary
folder that sees the repository's models (so what the examples write stays there); every
public name of casmech has its section."""

from __future__ import annotations

import re

import casmech
from tests.conftest import ROOT

PAGE = ROOT / "docs" / "api.md"
BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)


def test_every_public_name_has_a_section():
    headings = {line[4:].replace("\\", "").strip()
                for line in PAGE.read_text(encoding="utf-8").splitlines()
                if line.startswith("### ")}
    missing = {f"casmech.{name}" for name in casmech.__all__} - headings
    assert not missing


def test_the_examples_run(tmp_path, monkeypatch):
    (tmp_path / "models").symlink_to(ROOT / "models")
    monkeypatch.chdir(tmp_path)
    blocks = BLOCK.findall(PAGE.read_text(encoding="utf-8"))
    assert len(blocks) >= 10
    namespace: dict = {"__name__": "api_doc"}
    for k, block in enumerate(blocks):
        exec(compile(block, f"{PAGE}[block {k + 1}]", "exec"), namespace)  # noqa: S102
    assert (tmp_path / "dp_player.html").stat().st_size > 10_000  # the player's page
