"""The compiled-model cache's folder (backends.cache): $CASMECH_CACHE_DIR, else the
platform's user cache folder."""

from __future__ import annotations

import os
from pathlib import Path

ENVIRONMENT = "CASMECH_CACHE_DIR"


def cache_dir() -> Path:
    """$CASMECH_CACHE_DIR, else the platform's user cache folder for casmech."""
    configured = os.environ.get(ENVIRONMENT)
    if configured:
        return Path(configured)
    import platformdirs  # imported on use: a run with $CASMECH_CACHE_DIR never needs it

    return platformdirs.user_cache_path("casmech", appauthor=False)
