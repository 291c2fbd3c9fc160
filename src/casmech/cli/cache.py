"""casmech cache info|clear: the compiled-model cache ($CASMECH_CACHE_DIR, else the platform's
user cache folder: codegen.cache)."""

from __future__ import annotations

import json

from casmech.backends import cache
from casmech.backends.checked_model import FOLDER
from casmech.backends.manifest import MANIFEST
from casmech.errors import escape


def add_arguments(parser) -> None:
    parser.add_argument("action", choices=["info", "clear"])


def _describe(entry) -> str:
    try:
        info = json.loads((entry / MANIFEST).read_text(encoding="utf-8"))
        if not isinstance(info, dict):
            raise ValueError("not a mapping")
    except (OSError, UnicodeDecodeError, ValueError):
        return (f"  {entry.name}  damaged: its {MANIFEST} does not read (the next build of "
                "this key replaces it; `casmech cache clear` removes it)")
    return (f"  {entry.name}  {info.get('model', '?')}  {cache.size(entry) / 1e6:.2f} MB  "
            f"casmech {info.get('casmech')} casadi {info.get('casadi')} "
            f"{' '.join(info.get('flags', []))}")


def run(args) -> int:
    root = cache.cache_dir()
    if args.action == "clear":
        freed = cache.clear(root)
        print(f"cleared {root} ({freed / 1e6:.2f} MB freed)")
        return 0
    entries = cache.entries(root)
    total = sum(cache.size(entry) for entry in entries)
    print(f"{root}: {len(entries)} compiled models, {total / 1e6:.2f} MB")
    for entry in entries:
        print(escape(_describe(entry)))  # a model's name may hold control characters
    unfinished = cache.unfinished(root)
    if unfinished:
        stale = sum(cache.size(path) for path in unfinished)
        print(f"  and {len(unfinished)} unfinished builds ({stale / 1e6:.2f} MB: in progress, "
              f"or left by a build that was killed; `casmech cache clear` removes them)")
    kept = [p for p in (root / FOLDER).glob("*") if p.is_dir()] \
        if (root / FOLDER).is_dir() else []
    if kept:
        print(f"  and {len(kept)} checked models kept for runs of unchanged files "
              f"({sum(cache.size(p) for p in kept) / 1e6:.2f} MB)")
    return 0
