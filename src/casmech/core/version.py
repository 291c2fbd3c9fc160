"""casmech's version (casmech.__version__; in build manifests, metadata and the player)."""

VERSION = "0.1.0"
