"""`casmech.show`: the HTML player of a run in a Jupyter notebook (or saved as a file).

The page is the one `casmech animate` writes (html_player.py), shown in an iframe whose
`srcdoc` holds it, so that it keeps its own Content-Security-Policy and needs no server, no
network and no notebook extension; the notebook file holds the page (about 0.6 MB of three.js
plus the frames).
"""

from __future__ import annotations

import html
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from casmech.errors import UsageError

HEIGHT = 520  # pixels of the iframe in a notebook


class Player:
    """A run's player: `_repr_html_` draws it in a notebook, `save(path)` writes the page."""

    def __init__(self, page: str, name: str, frames: int, bodies: int, height: int = HEIGHT):
        self.page, self.name, self.frames, self.bodies = page, name, frames, bodies
        self.height = int(height)

    def _repr_html_(self) -> str:
        return (f'<iframe srcdoc="{html.escape(self.page, quote=True)}" title="casmech player: '
                f'{html.escape(self.name, quote=True)}" sandbox="allow-scripts" '
                f'style="width: 100%; height: {self.height}px; border: 1px solid #ccc">'
                "</iframe>")

    def save(self, path: str | Path) -> Path:
        """Write the page (one offline HTML file, as `casmech animate` writes it)."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(self.page, encoding="utf-8")
        return path

    def __repr__(self) -> str:
        return f"Player({self.name}: {self.frames} frames, {self.bodies} bodies)"


def _table(results) -> tuple[list[str], np.ndarray, dict]:
    """(names, values, metadata) of a Result, a results DataFrame or a results folder/file."""
    from casmech.io.frames import load_results

    if hasattr(results, "functions") and hasattr(results, "to_dataframe"):  # an API Result
        results = results.to_dataframe()
    elif isinstance(results, (str, Path)):
        results = load_results(results)
    if not (hasattr(results, "index") and hasattr(results, "columns")):
        raise UsageError(f"casmech.show: expected a Result of casmech.analyze, a DataFrame of "
                         f"casmech.load_results or a results folder, got "
                         f"{type(results).__name__}")
    names = ["t", *map(str, results.columns)]
    values = np.column_stack([np.asarray(results.index, float), np.asarray(results, float)])
    return names, values, dict(results.attrs.get("metadata") or {})


def _model(model, metadata: Mapping, functions) -> Any:
    """The ResolvedModel to draw: the one given (or its file), else the Result's model with
    its parameter values, else the model file the run's metadata names with its overrides."""
    from casmech.schema import load_model, load_model_text

    if model is not None:
        return model if hasattr(model, "bodies") else load_model(model)
    if functions is not None:
        ir = functions.ir
        plain = load_model_text(ir.text, ir.file)
        changed = {name: repr(float(value)) for name, value in ir.parameters.items()
                   if plain.parameters.get(name) != value}
        return load_model_text(ir.text, ir.file, changed) if changed else plain
    described = metadata.get("model") if isinstance(metadata.get("model"), Mapping) else {}
    path = described.get("absolute_path")
    if not path or not Path(path).is_file():
        raise UsageError("casmech.show: these results do not name a model file that exists "
                         "(hint: pass the model: casmech.show(results, model='model.yaml'))")
    return load_model(path, overrides=dict(metadata.get("overrides") or {}))


def show(results, model=None, *, trails: Sequence[str] = (), every: int | None = None,
         fps: float | None = None, height: int = HEIGHT) -> Player:
    """The player of a run for a notebook: `results` is a Result of casmech.analyze, a
    DataFrame of casmech.load_results or a results folder or file (`casmech run --out DIR`);
    `model` (a loaded model or its file) is needed only when the results do not say which
    (a Result knows its model, a run's metadata its file and overrides). `trails`: body points
    to draw the paths of (`"BODY"` or `"BODY@X,Y,Z"`, as `casmech animate --trail`); `every`
    / `fps`: which rows to draw (as `--every` / `--fps`)."""
    from casmech.io.animate import build_scene
    from casmech.io.html_player import render_html
    from casmech.io.overlays import build_overlays

    names, values, metadata = _table(results)
    loaded = _model(model, metadata, getattr(results, "functions", None))
    scene = build_scene(loaded, names, values, every=every, fps=fps)
    overlays = build_overlays(loaded, scene, names, values, scene.rows, metadata, trails)
    return Player(render_html(scene, overlays), scene.name, len(scene.times),
                  len(scene.bodies), height)
