"""Build generated C sources into one shared library: units compiled in parallel, then linked."""

from __future__ import annotations

import json
import os
import shlex
import shutil
import sys
from dataclasses import field
from functools import lru_cache
from pathlib import Path

from casmech.backends import stamps
from casmech.backends.folder import cache_dir
from casmech.core.records import record
from casmech.errors import AnalysisError, UsageError

# -O1: the generated functions run much faster than at -O0 for a build -O2 would lengthen more
# than it speeds the calls (docs/decisions/codegen-flags.md). casmech compile --flags, or
# CASMECH_CFLAGS, choose others.
DEFAULT_FLAGS = ("-O1",)
# a shared library's file suffix on this platform (what casadi.external's dlopen/LoadLibrary
# expects)
SUFFIX = {"win32": ".dll", "cygwin": ".dll", "darwin": ".dylib"}.get(sys.platform, ".so")
LIBRARY = f"libcasmech_model{SUFFIX}"
# c99: glibc's gnu-mode gamma() clashes with ours; -fPIC: position-independent code where a
# shared library needs it (Windows DLLs do not: gcc there warns of the flag)
REQUIRED_FLAGS = ("-std=c99",) + (() if SUFFIX == ".dll" else ("-fPIC",))
COMPILERS = ("gcc", "clang", "cc")  # the first found on PATH is the default without $CC
FLAGS_ENVIRONMENT = "CASMECH_CFLAGS"  # replaces DEFAULT_FLAGS when set
# the instruction set of the joint system's loop functions where the building machine has it
# (machine_flags): AVX's three-operand scalar instructions need no register copies, which makes
# their straight-line code a fifth shorter; no FMA, so the same roundings
# (docs/decisions/joint-ode-code-size.md)
AVX_FLAGS = ("-mavx",)
CPU_INFO = Path("/proc/cpuinfo")


def default_compiler() -> str:
    """$CC, else the first of COMPILERS on PATH (else "gcc", which `available` reports
    missing)."""
    configured = os.environ.get("CC")
    if configured:
        return configured
    return next((name for name in COMPILERS if shutil.which(name)), COMPILERS[0])


@lru_cache(maxsize=1)
def machine_flags() -> tuple[str, ...]:
    """AVX_FLAGS on an x86-64 Linux machine whose kernel reports AVX (its first processor's
    `flags` in CPU_INFO), else none; a library built with them is keyed by them, so that a
    machine without AVX never loads it."""
    import platform

    if sys.platform != "linux" or platform.machine() not in ("x86_64", "AMD64"):
        return ()
    try:
        with CPU_INFO.open(encoding="ascii", errors="replace") as info:
            for line in info:
                if line.startswith("flags"):
                    return AVX_FLAGS if "avx" in line.partition(":")[2].split() else ()
    except OSError:
        pass
    return ()


@lru_cache(maxsize=8)
def takes_machine_flags(compiler: str) -> bool:
    """Whether `compiler` (a command, a launcher may lead) is one whose -m options
    machine_flags gives: a word of it that is, or links to, a gcc, clang or Intel compiler
    (cc is usually a link to gcc); another compiler gets none."""
    for word in shlex.split(compiler):
        found = shutil.which(word)
        for name in {os.path.basename(word), os.path.basename(os.path.realpath(found or word))}:
            if "gcc" in name or "clang" in name or name.startswith(("icx", "icc")):
                return True
    return False


def default_flags() -> tuple[str, ...]:
    configured = os.environ.get(FLAGS_ENVIRONMENT)
    return tuple(configured.split()) if configured is not None else DEFAULT_FLAGS


@record
class Toolchain:
    """A C compiler ($CC, default the first of gcc, clang, cc found; a launcher may lead:
    "ccache gcc") and the flags every unit is compiled with ($CASMECH_CFLAGS, default
    DEFAULT_FLAGS; REQUIRED_FLAGS always)."""

    compiler: str = field(default_factory=default_compiler)
    flags: tuple[str, ...] = field(default_factory=lambda: default_flags())
    jobs: int = field(default_factory=lambda: os.cpu_count() or 1)
    # (function name, flags) pairs: those functions' units compiled with these flags instead
    # (backends.library groups a library's functions by them)
    function_flags: tuple[tuple[str, tuple[str, ...]], ...] = ()

    @property
    def all_flags(self) -> tuple[str, ...]:
        return REQUIRED_FLAGS + tuple(self.flags)

    def flags_of(self, name: str) -> tuple[str, ...]:
        """The flags of function `name`'s unit (REQUIRED_FLAGS apart)."""
        return dict(self.function_flags).get(name, tuple(self.flags))

    def version(self) -> str:
        return compiler_version(self.compiler)


@lru_cache(maxsize=8)
def compiler_version(compiler: str) -> str:
    """First line of `compiler --version`, or "" when there is no such compiler; remembered
    across processes for as long as the programs the command names stay the same files
    (backends.stamps: the path each word resolves to on PATH, and that file's identity, size
    and times)."""
    command = shlex.split(compiler)
    programs = [shutil.which(word) for word in command]
    if not command or programs[0] is None:
        return ""
    files = [os.path.realpath(path) for path in programs if path is not None]
    return stamps.remembered(json.dumps(["compiler version", compiler, programs]), files,
                             lambda: _version(command), _one_line, cache_dir())


def _version(command: list[str]) -> str:
    import subprocess  # imported on use (as in _run): a warm run's version is remembered

    try:
        done = subprocess.run([*command, "--version"], capture_output=True, text=True,
                              timeout=30, check=False)
    except OSError:
        return ""
    return done.stdout.splitlines()[0].strip() if done.returncode == 0 and done.stdout else ""


def _one_line(text: str) -> bool:
    """Whether a stored text is one a version reads as: a non-empty printable line."""
    return 0 < len(text) <= 500 and text.isprintable()


def available(toolchain: Toolchain | None = None) -> bool:
    return bool((toolchain or Toolchain()).version())


def _run(command: list[str], cwd: Path) -> None:
    import subprocess

    done = subprocess.run(command, cwd=cwd, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise AnalysisError(f"the C compiler failed: {' '.join(command)}\n"
                            f"{done.stderr.strip()[-4000:]}")


def build_libraries(libraries: dict[str, list[Path]], directory: Path,
                    toolchain: Toolchain, unit_flags: dict[str, tuple[str, ...]] | None = None
                    ) -> list[Path]:
    """Compile every source to an object (toolchain.jobs at a time, all libraries in one pool,
    the longest sources first) and link each library (file name -> its sources). unit_flags:
    source file name -> its flags instead of toolchain.flags (REQUIRED_FLAGS always)."""
    if not available(toolchain):
        raise UsageError(f"no C compiler '{toolchain.compiler}' found; install gcc or clang "
                         "(on Windows: MinGW-w64's gcc) or set CC, "
                         "or use mode='interpreted' (casmech run --mode interpreted)")
    compiler, flags = shlex.split(toolchain.compiler), list(toolchain.all_flags)
    unit_flags = unit_flags or {}
    sources = [src for group in libraries.values() for src in group]
    commands = [[*compiler, *REQUIRED_FLAGS, *unit_flags[src.name], "-c", src.name, "-o",
                 src.stem + ".o"] if src.name in unit_flags else
                [*compiler, *flags, "-c", src.name, "-o", src.stem + ".o"]
                for src in sorted(sources, key=lambda src: -src.stat().st_size)]
    from concurrent.futures import ThreadPoolExecutor  # (with logging: a build's only)

    with ThreadPoolExecutor(max_workers=max(1, toolchain.jobs)) as pool:
        list(pool.map(lambda command: _run(command, directory), commands))
    for library, group in libraries.items():
        _run([*compiler, *flags, "-shared", *(src.stem + ".o" for src in group), "-o", library,
              "-lm"], directory)
    for src in sources:
        (directory / (src.stem + ".o")).unlink()
    return [directory / library for library in libraries]


def build_library(sources: list[Path], directory: Path, toolchain: Toolchain) -> Path:
    """Compile the sources (toolchain.jobs at a time) and link LIBRARY."""
    return build_libraries({LIBRARY: sources}, directory, toolchain)[0]
