"""A progress bar for `casmech run`: simulated time / t_end, wall time, rows (tqdm, on stderr).

Drawn only when the stream is a terminal, and only once the run has lasted DELAY seconds
(environment variable CASMECH_PROGRESS_DELAY overrides it, e.g. 0 to always draw); silent
otherwise, so logs and pipes never receive carriage-return noise.
"""

from __future__ import annotations

import os
import sys
from contextlib import contextmanager

DELAY = 1.0  # [s] a run shorter than this never shows a bar
FALLBACK_WIDTH = 100  # columns when the terminal reports none (tqdm would draw nothing)
BAR = ("{desc}{percentage:3.0f}%|{bar}| t = {n:.4g}/{total:.4g} s "
       "[wall {elapsed}<{remaining}{postfix}]")  # tqdm puts ", " before a postfix


def delay() -> float:
    return float(os.environ.get("CASMECH_PROGRESS_DELAY", DELAY))


class _Bar:
    """callback(t) for casmech.analyze(progress=...): moves the bar to simulated time t."""

    def __init__(self, tqdm, t_end: float, stream):
        self.rows = 0
        width = terminal_width(stream)
        self.bar = tqdm(total=float(t_end), file=stream, delay=delay(), bar_format=BAR,
                        desc="casmech run ", ncols=width or FALLBACK_WIDTH,
                        dynamic_ncols=bool(width), leave=True)

    def __call__(self, t: float) -> None:
        self.rows += 1
        self.bar.set_postfix_str(f"{self.rows} rows", refresh=False)
        self.bar.update(min(float(t), self.bar.total) - self.bar.n)

    def close(self) -> None:
        self.bar.close()


@contextmanager
def progress_bar(t_end: float, stream=None, quiet: bool = False):
    """Yields the callback for casmech.analyze, or None when no bar is to be drawn (quiet, the
    stream is not a terminal, or tqdm is not installed)."""
    stream = sys.stderr if stream is None else stream
    tqdm = tqdm_class() if is_terminal(stream) and not quiet else None
    if tqdm is None:
        yield None
        return
    bar = _Bar(tqdm, t_end, stream)
    try:
        yield bar
    finally:
        bar.close()


def terminal_width(stream) -> int:
    """The terminal's columns; 0 when it does not say (a pseudo-terminal never sized)."""
    try:
        return os.get_terminal_size(stream.fileno()).columns
    except (AttributeError, OSError, ValueError):
        return 0


def is_terminal(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # no isatty, or a closed stream
        return False


def tqdm_class():
    try:
        from tqdm import tqdm
    except ImportError:
        return None
    return tqdm
