"""build.machine_flags: AVX_FLAGS on an x86-64 Linux machine whose kernel reports AVX (the
first processor's `flags` line of /proc/cpuinfo), none elsewhere or where the file cannot be
read."""

import platform

import pytest

from casmech.backends import build

CPU = """processor\t: 0
vendor_id\t: AuthenticAMD
flags\t\t: fpu sse2 {extra} sse4_2
bugs\t\t: sysret_ss_attrs

processor\t: 1
flags\t\t: fpu sse2 avx
"""


@pytest.fixture
def cpu_info(tmp_path, monkeypatch):
    """Writes a CPU_INFO of the given first processor's extra flags; machine_flags reads it
    afresh on x86-64 Linux."""
    monkeypatch.setattr(build.sys, "platform", "linux")
    monkeypatch.setattr(platform, "machine", lambda: "x86_64")
    path = tmp_path / "cpuinfo"
    monkeypatch.setattr(build, "CPU_INFO", path)
    build.machine_flags.cache_clear()

    def write(extra: str | None) -> None:
        if extra is not None:
            path.write_text(CPU.format(extra=extra))
        build.machine_flags.cache_clear()

    yield write
    build.machine_flags.cache_clear()


@pytest.mark.parametrize(("extra", "want"), [
    ("avx avx2", build.AVX_FLAGS),
    ("avx2 avx512f", ()),  # the word avx itself, of the first processor
    ("ssse3", ()),
    (None, ()),  # no such file
])
def test_avx_where_the_first_processor_reports_it(cpu_info, extra, want):
    cpu_info(extra)
    assert build.machine_flags() == want


def test_none_on_other_machines(cpu_info, monkeypatch):
    cpu_info("avx")
    monkeypatch.setattr(platform, "machine", lambda: "aarch64")
    assert build.machine_flags() == ()
    build.machine_flags.cache_clear()
    monkeypatch.setattr(platform, "machine", lambda: "x86_64")
    monkeypatch.setattr(build.sys, "platform", "darwin")
    assert build.machine_flags() == ()


@pytest.mark.parametrize("compiler, takes", [
    ("gcc", True), ("gcc-12", True), ("ccache clang", True), ("x86_64-linux-gnu-gcc", True),
    ("icx", True), ("tcc", False), ("/opt/some/cl", False)])
def test_machine_flags_only_for_compilers_that_take_them(compiler, takes):
    """-mavx goes to gcc, clang and Intel compilers (by name, or the file a name links to),
    never to another compiler, which might reject it."""
    build.takes_machine_flags.cache_clear()
    assert build.takes_machine_flags(compiler) is takes


def test_cc_linked_to_gcc_takes_them(tmp_path, monkeypatch):
    """A `cc` that is a link to gcc (as Debian's alternatives make it) takes the flags."""
    gcc = tmp_path / "x86_64-linux-gnu-gcc-12"
    gcc.write_text("#!/bin/sh\n")
    gcc.chmod(0o755)
    (tmp_path / "cc").symlink_to(gcc)
    monkeypatch.setenv("PATH", str(tmp_path))
    build.takes_machine_flags.cache_clear()
    assert build.takes_machine_flags("cc") is True
    build.takes_machine_flags.cache_clear()
