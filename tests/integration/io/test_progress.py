"""The progress bar of casmech run: drawn on a terminal (a real pseudo-terminal), silent on a
pipe, silent on a terminal for a run shorter than the delay."""

import fcntl
import io
import os
import pty
import re
import select
import struct
import subprocess
import sys
import termios
from pathlib import Path

import pytest

from casmech.io.csv import read_csv
from casmech.io.progress import progress_bar
from tests.conftest import MODELS

SCRIPT = Path(sys.executable).parent / "casmech"
RUN = [str(SCRIPT), "run", str(MODELS / "slider_crank.yaml"), "--t-end", "0.5"]


def run_on_terminal(out, delay: str, columns: int = 120) -> str:
    """casmech run with stderr on a pseudo-terminal; everything the terminal received."""
    try:
        master, slave = pty.openpty()
    except OSError as error:  # a machine without /dev/ptmx cannot host this test
        pytest.skip(f"no pseudo-terminal: {error}")
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, columns, 0, 0))
    env = {**os.environ, "CASMECH_PROGRESS_DELAY": delay}
    process = subprocess.Popen([*RUN, "--out", str(out)], stdin=subprocess.DEVNULL,
                               stdout=subprocess.DEVNULL, stderr=slave, env=env)
    os.close(slave)
    received = b""
    while True:  # read until the child closes its end (EOF or EIO on Linux)
        ready, _, _ = select.select([master], [], [], 60)
        try:
            chunk = os.read(master, 4096) if ready else b""
        except OSError:
            chunk = b""
        if not chunk:
            break
        received += chunk
    os.close(master)
    assert process.wait(timeout=60) == 0
    return received.decode("utf-8", "replace")


@pytest.mark.parametrize("columns", [120, 0])  # 0: a terminal that never says its size
def test_drawn_on_a_terminal(tmp_path, columns):
    """Delay 0 stands in for a run longer than a second: the final bar shows the whole
    simulated span, the row count of the CSV written by the same run, and the wall time."""
    screen = run_on_terminal(tmp_path, "0", columns)
    _, values = read_csv(tmp_path / "results.csv")
    final = screen.replace("\r", "\n").strip().splitlines()[-1]
    assert "100%" in final and "t = 0.5/0.5 s" in final
    assert f"{len(values)} rows" in final and len(values) == 51
    assert re.search(r"wall \d\d:\d\d<", final)
    assert len(final) <= (columns or 100)  # fits the terminal (or the fallback width)


def test_silent_on_a_terminal_for_a_short_run(tmp_path):
    assert run_on_terminal(tmp_path, "1") == ""  # the run takes ~0.1 s here


def test_silent_when_stderr_is_not_a_terminal(tmp_path):
    env = {**os.environ, "CASMECH_PROGRESS_DELAY": "0"}
    done = subprocess.run([*RUN, "--out", str(tmp_path)], capture_output=True, text=True,
                          env=env, timeout=60)
    assert done.returncode == 0 and done.stderr == ""


def test_callback_moves_the_bar_to_simulated_time(monkeypatch):
    class Terminal(io.StringIO):
        def isatty(self):
            return True

    monkeypatch.setenv("CASMECH_PROGRESS_DELAY", "0")
    screen = Terminal()
    with progress_bar(2.0, screen) as callback:
        for t in (0.0, 0.5, 1.0):
            callback(t)
        assert callback.bar.n == 1.0 and callback.rows == 3
    assert "t = 1/2 s" in screen.getvalue() and "3 rows" in screen.getvalue()
    with progress_bar(2.0, io.StringIO()) as callback:  # not a terminal: no callback at all
        assert callback is None
