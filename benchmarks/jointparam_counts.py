"""n_instructions of the numeric joint functions (formulations.joint_system.build over a lowered
IR), as JSON: run before and after a change of the joint build and diff the outputs
(docs/decisions/joint-system-over-model-data.md).

    PYTHONPATH=src:. python benchmarks/jointparam_counts.py > counts.json
"""

import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

import systems  # noqa: E402
from casmech_model import yaml_text  # noqa: E402

import casmech  # noqa: E402
from casmech.formulations.joint_system import build  # noqa: E402
from casmech.formulations.tree import spanning_tree  # noqa: E402

MODELS = {"chain8": lambda: casmech.loads(yaml_text(systems.chain(8))),
          "four_bar": lambda: casmech.load(ROOT / "benchmarks/models/four_bar.yaml"),
          "zoo": lambda: casmech.load(ROOT / "tests/helpers/joint_zoo.yaml"),
          "four_bar_models": lambda: casmech.load(ROOT / "models/four_bar.yaml"),
          "double_pendulum": lambda: casmech.load(ROOT / "models/double_pendulum.yaml"),
          "bricard": lambda: casmech.load(ROOT / "models/bricard.yaml")}

counts = {}
for name, model in MODELS.items():
    functions = casmech.compile(model())
    system = build(functions.ir, spanning_tree(functions.ir))
    counts[name] = {f: getattr(system, f).n_instructions() for f in (
        "dynamics", "motion", "velocity_jacobian", "acceleration_system", "relative_states")}
print(json.dumps(counts, indent=1))
