"""A small C program that times calls without Python around them, for the benchmarks that cost
single calls of generated functions (ode_flags.py, rosenbrock_estimate.py): PRELUDE (the
headers, the generated functions' signature `fn`, `now()` the process's CPU time) before each
script's own `main`, built by gcc -O2."""

from __future__ import annotations

import subprocess
from pathlib import Path

PRELUDE = r"""
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
typedef long long ci;
typedef int (*fn)(const double**, double**, ci*, double*, int);
static double now(void) {
  struct timespec s;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &s);
  return s.tv_sec + 1e-9 * s.tv_nsec;
}
"""


def build(folder: Path, body: str) -> Path:
    """The program PRELUDE + `body` built in `folder`; its path."""
    source, program = Path(folder) / "harness.c", Path(folder) / "harness"
    source.write_text(PRELUDE + body)
    subprocess.run(["gcc", "-O2", "-o", str(program), str(source), "-ldl", "-lm"], check=True)
    return program
