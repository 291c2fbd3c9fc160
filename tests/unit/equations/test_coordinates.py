"""The state force laws read (equations/coordinates.py): bound in an order independent of the
process, so the parametric library's structure signature (its cache key) is too."""

import os
import subprocess
import sys

from tests.conftest import MODELS, ROOT

SIGNATURE = """
import casmech
from casmech.model.lower import lower
from casmech.model.parametric import split
print(split(lower(casmech.load({path!r}))).signature)
"""


def test_the_signature_of_a_model_reading_the_state_is_the_same_in_every_process():
    """Two processes with different string hashes (PYTHONHASHSEED) give one signature for a
    model whose force laws read four states (a set of names, iterated by hash)."""
    code = SIGNATURE.format(path=str(MODELS / "user_force_pendulum.yaml"))
    source = str(ROOT / "src")
    found = set()
    for seed in ("0", "1", "2"):
        env = {**os.environ, "PYTHONHASHSEED": seed,
               "PYTHONPATH": os.pathsep.join([source, os.environ.get("PYTHONPATH", "")])}
        done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                              text=True, check=True)
        found.add(done.stdout.strip())
    assert len(found) == 1
