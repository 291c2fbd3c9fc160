"""Time runtime.assembly.assemble_positions: cold (the first call on a fresh bundle, which builds
the closest-point rootfinder when one is needed) and warm (the second call), medians of
--repeats, from the file's pose and from it moved by 1e-3 (random, every coordinate), for
models/four_bar.yaml (0 DOF), benchmarks/models/four_bar.yaml (1 DOF) and chain32 (96 DOF).

    PYTHONPATH=src python benchmarks/assembly_time.py
    PYTHONPATH=/path/to/other/src python benchmarks/assembly_time.py   # another checkout
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np
from casmech_model import yaml_text
from systems import make

import casmech
from casmech.runtime import assembly

HERE = Path(__file__).parent


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    texts = {"four_bar (0 DOF)": (HERE.parent / "models" / "four_bar.yaml").read_text(),
             "four_bar (1 DOF)": (HERE / "models" / "four_bar.yaml").read_text(),
             "chain32 (96 DOF)": yaml_text(make("chain32"))}
    for name, text in texts.items():
        for size in (0.0, 1e-3):
            cold, warm = [], []
            for _ in range(args.repeats):
                functions = casmech.compile(casmech.loads(text), "interpreted")
                guess = assembly.initial_guess(functions)
                start = guess + size * np.random.default_rng(0).standard_normal(guess.size)
                for times in (cold, warm):
                    begin = time.perf_counter()
                    assembly.assemble_positions(functions, 0.0, start)
                    times.append(time.perf_counter() - begin)
            where = "file" if size == 0 else "file + 1e-3"
            print(f"{name:18s} from {where:12s} cold {1e3 * statistics.median(cold):7.2f} ms, "
                  f"warm {1e3 * statistics.median(warm):7.2f} ms", flush=True)


if __name__ == "__main__":
    main()
