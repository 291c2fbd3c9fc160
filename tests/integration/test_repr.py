"""The short repr of what casmech.load and casmech.compile return: one line with the name,
counts, degrees of freedom (closed forms: a double pendulum's 2, a driven four-bar's 0, a
free body's 6) and mode, never the YAML text."""

from __future__ import annotations

import pytest

import casmech
from tests.conftest import MODELS

FREE_BODY = """casmech: 1
name: tumbling
bodies:
  - {name: brick, mass: 1, inertia: [1, 2, 3], position: [0, 0, 0]}
analysis: {type: dynamics, t_end: 1}
"""


@pytest.mark.parametrize(("model", "start", "dof"), [
    (MODELS / "double_pendulum.yaml", "CompiledModel('double_pendulum': 2 bodies, 2 joints", 2),
    (MODELS / "four_bar.yaml", "CompiledModel('four_bar': 3 bodies, 4 joints", 0),
    (FREE_BODY, "CompiledModel('tumbling': 1 body, 0 joints", 6),
])
def test_compiled_repr_is_one_short_line_with_the_dof(model, start, dof):
    loaded = casmech.loads(model) if isinstance(model, str) else casmech.load(model)
    compiled = casmech.compile(loaded)
    text = repr(compiled)
    assert text.startswith(start) and f", {dof} DOF; interpreted" in text
    assert compiled.dof == dof
    assert "\n" not in text and len(text) < 200 and "casmech: 1" not in text
    assert "\n" not in repr(loaded) and "casmech: 1" not in repr(loaded)
    assert repr(loaded).startswith(f"ResolvedModel('{loaded.name}'")
