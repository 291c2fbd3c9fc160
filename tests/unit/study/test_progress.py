"""casmech.study.progress: a bar over runs on a terminal, counting failures; none on a pipe."""

import io

from casmech.study.progress import runs_bar


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_bar_counts_runs_and_failures(monkeypatch):
    monkeypatch.setenv("CASMECH_PROGRESS_DELAY", "0")
    stream = Terminal()
    with runs_bar(3, stream) as done:
        for status in ("complete", "failed", "complete"):
            done(status)
    text = stream.getvalue()
    assert "3/3 runs" in text and "1 failed" in text


def test_no_bar_on_a_pipe():
    stream = io.StringIO()
    with runs_bar(3, stream) as done:
        assert done is None
    assert stream.getvalue() == ""
