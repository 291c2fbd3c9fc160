"""The plain lowering (no symbolic parameters) is what it was before the lowering learned
traced numbers (and before numbers took units, `initial:` and `outputs:` came: the fields and
geometry they added are skipped while unused, ADDED): the structure of the ModelIR of every
model in models/ (names, indices, kinds, expression texts, settings) hashes to the fingerprint
in tests/reference/plain_lowering.json, and its numbers (all of them, zeros and round-off
included) are the ones kept in tests/reference/plain_lowering_values.npz to the last bits
that the CPU's BLAS kernels decide. The kept numbers hash to the fingerprints' "values", which
tests/reference/README.md says how they were made (this file's `fingerprint`, run on the
source of commit 1365157, before traced numbers).

`python -m tests.unit.model.test_plain_lowering` prints the fingerprints of the source it runs.
"""

import hashlib
import json
from dataclasses import fields, is_dataclass
from pathlib import Path

import numpy as np
import pytest

from casmech.model.lower import lower
from casmech.schema import load_model
from casmech.schema.resolved import Analysis
from tests.conftest import ROOT

# models written with what the reference's source could not read (units, `initial:`,
# `outputs:`, couplings, screws, a kinematic `estimate:`): no fingerprint of theirs can exist
NEWER = frozenset({"four_bar_released.yaml", "gear_pair.yaml", "lead_screw.yaml",
                   "four_bar_synthesis.yaml"})
MODELS = sorted(p for p in (ROOT / "models").rglob("*.yaml")
                if p.parent.name != "components" and p.name not in NEWER)
REFERENCE = ROOT / "tests" / "reference" / "plain_lowering.json"
VALUES = ROOT / "tests" / "reference" / "plain_lowering_values.npz"
SKIPPED = frozenset({"file", "text", "source", "sources"})  # paths that depend on the checkout
# fields added to the IR after the reference was made, skipped while they hold their default
# (a model without `outputs:` or `initial:`), and the joint geometry entries added for the
# spherical joint's state (q@i, q@j: equations/joint_states.py)
ADDED = {"outputs": (), "reference_pose": None, "initial": {}, "initial_sources": {},
         "others": (), "couples": (), "coefficients": ()}
ADDED_GEOMETRY = frozenset({"q@i", "q@j"})
# entries of a table added after the reference, skipped while they hold their default: a
# contact friction's `exact` (model: smooth)
ADDED_ENTRIES = {"exact": 0.0}
# the analysis options as the reference's IR held them, with their defaults
OLD_OPTIONS = {"formulation": "auto", "stabilization": "ggl", "method": "auto", "at": None,
               "inputs": None}


def _added(name: str, value) -> bool:
    """Whether the field is one of ADDED holding its default (another field of that name,
    a table's `coefficients` array, is no such field)."""
    if name not in ADDED:
        return False
    default = ADDED[name]
    return value is None if default is None else (type(value) is type(default)
                                                  and value == default)


def _walk(value, numbers: list, tokens: list) -> None:
    if isinstance(value, (bool, str, int, range, type(None))):
        tokens.append(repr(value))
    elif isinstance(value, (float, np.floating)):
        numbers.append(float(value))
        tokens.append("#")
    elif isinstance(value, np.ndarray):
        tokens.append(f"#{value.shape}{value.dtype}")
        numbers.extend(np.asarray(value, float).ravel().tolist())
    elif hasattr(value, "text") and hasattr(value, "root"):  # an expression: its text
        tokens.append(f"expr {value.text}")
    elif isinstance(value, Analysis):  # its options as the reference held them (a mapping
        tokens.append(type(value).__name__)  # of these keys; typed options came after it)
        for item in fields(value):
            if item.name == "options":
                tokens.append(item.name)
                _walk({key: getattr(value.options, key, default)
                       for key, default in OLD_OPTIONS.items()}, numbers, tokens)
            elif item.name not in (*SKIPPED, "written"):
                tokens.append(item.name)
                _walk(getattr(value, item.name), numbers, tokens)
    elif is_dataclass(value):
        tokens.append(type(value).__name__)
        for item in fields(value):
            if item.name not in SKIPPED and not _added(item.name, getattr(value, item.name)):
                tokens.append(item.name)
                _walk(getattr(value, item.name), numbers, tokens)
    elif isinstance(value, dict) or hasattr(value, "items"):
        kept = {key: item for key, item in value.items() if key not in ADDED_GEOMETRY
                and not (key in ADDED_ENTRIES and item == ADDED_ENTRIES[key])}
        tokens.append(f"{{{len(kept)}")
        for key, item in kept.items():
            tokens.append(str(key))
            _walk(item, numbers, tokens)
    elif isinstance(value, (tuple, list)):
        tokens.append(f"({len(value)}")
        for item in value:
            _walk(item, numbers, tokens)
    else:
        tokens.append(type(value).__name__)


def _numbers_and_tokens(path: Path) -> tuple[np.ndarray, list[str]]:
    numbers: list[float] = []
    tokens: list[str] = []
    _walk(lower(load_model(path)), numbers, tokens)
    return np.array(numbers, float), tokens


def _sha256(numbers: np.ndarray) -> str:
    return hashlib.sha256(numbers.tobytes()).hexdigest()


def fingerprint(path: Path) -> dict:
    """The count and sha256 of every number of the model's plain lowering, and the sha256 of
    its structure."""
    numbers, tokens = _numbers_and_tokens(path)
    return {"numbers": len(numbers), "values": _sha256(numbers),
            "structure": hashlib.sha256("\0".join(tokens).encode()).hexdigest()}


def _name(path: Path) -> str:
    return str(path.relative_to(ROOT / "models"))


@pytest.mark.parametrize("path", MODELS, ids=_name)
def test_plain_lowering_is_unchanged(path):
    reference = json.loads(REFERENCE.read_text())
    assert _name(path) in reference, f"no fingerprint for {_name(path)}: add it (module doc)"
    kept = reference[_name(path)]
    with np.load(VALUES) as values:
        expected = values[_name(path)]
    assert _sha256(expected) == kept["values"]  # the kept numbers are the fingerprinted ones
    numbers, tokens = _numbers_and_tokens(path)
    assert hashlib.sha256("\0".join(tokens).encode()).hexdigest() == kept["structure"]
    assert len(numbers) == kept["numbers"]
    # the last bits of a rotation's products depend on the CPU's OpenBLAS kernel: SkylakeX's
    # and Zen's differ by up to 5.6e-17 in these numbers (of sizes ~1e-2..1e2), and round-off
    # that is 1e-17 on one is 0.0 on the other; a change of the lowering moves far more
    np.testing.assert_allclose(numbers, expected, rtol=1e-14, atol=1e-15)


if __name__ == "__main__":
    print(json.dumps({_name(p): fingerprint(p) for p in MODELS}, indent=1, sort_keys=True))
