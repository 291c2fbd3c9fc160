"""A progress bar over a study's runs (tqdm, on stderr), drawn as output.progress draws a run's:
only on a terminal and only once the study has lasted output.progress.delay() seconds."""

from __future__ import annotations

import sys
from contextlib import contextmanager

from casmech.io import progress

BAR = "{desc}{percentage:3.0f}%|{bar}| {n}/{total} runs [wall {elapsed}<{remaining}{postfix}]"


@contextmanager
def runs_bar(total: int, stream=None):
    """Yields callback(status) to call once per finished run (None: no bar)."""
    stream = sys.stderr if stream is None else stream
    tqdm = progress.tqdm_class() if progress.is_terminal(stream) else None
    if tqdm is None:
        yield None
        return
    bar = tqdm(total=total, file=stream, delay=progress.delay(), bar_format=BAR,
               desc="casmech sweep ",
               ncols=progress.terminal_width(stream) or progress.FALLBACK_WIDTH)
    failed = 0

    def done(status: str) -> None:
        nonlocal failed
        failed += status != "complete"
        if failed:
            bar.set_postfix_str(f"{failed} failed", refresh=False)
        bar.update(1)

    try:
        yield done
    finally:
        bar.close()
