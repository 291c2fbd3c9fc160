"""casmech.show: the player of a Result, a DataFrame or a results folder for a notebook. Its
page is the one `casmech animate` writes for the same table, drawn from the model with the run's
parameter values, and its iframe plays in headless Chromium."""

import html
import json
import re

import numpy as np
import pytest

import casmech
from casmech import cli
from tests.conftest import MODELS
from tests.integration.io.test_animate_html import (  # noqa: F401 - chromium is a fixture
    BAR,
    browse,
    chromium,
    finish,
    read_png,
)

FOUR_BAR = MODELS / "four_bar.yaml"


def data_of(page: str) -> dict:
    found = re.search(r'<script type="application/json" id="casmech-data">(.*?)</script>',
                      page, re.S)
    return json.loads(found.group(1))


def coupler_length(data: dict) -> float:
    """Extent along the coupler's own x of its box part (the YAML's box: [b, w, w])."""
    index = data["bodies"].index("coupler")
    part = next(p for p in data["parts"] if p["body"] == index and p["joint"] < 0)
    points = np.reshape(part["points"], (-1, 3))
    return float(np.ptp(points[:, 0]))


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory):
    out = tmp_path_factory.mktemp("show") / "run"
    assert cli.main(["run", str(FOUR_BAR), "--out", str(out), "--t-end", "0.2",
                     "--set", "b=2.1"]) == 0
    return out


def test_show_a_result_draws_its_models_parameter_values():
    model = casmech.load(FOUR_BAR, {"b": "2.1"})
    result = casmech.analyze(casmech.compile(model), "inverse_dynamics", t_end=0.2)
    player = casmech.show(result)
    data = data_of(player.page)
    # the page keeps 7 significant digits
    assert coupler_length(data) == pytest.approx(2.1, rel=1e-6)
    assert (player.frames, player.bodies) == (len(result.times), 3)
    frame = result.to_dataframe()
    np.testing.assert_allclose(data["times"], frame.index, rtol=5e-7, atol=1e-12)
    assert repr(player) == f"Player(four_bar: {len(result.times)} frames, 3 bodies)"


def test_show_a_results_folder_is_the_animate_page(run_folder, tmp_path):
    player = casmech.show(run_folder)  # the model and --set b=2.1 from metadata.json
    assert coupler_length(data_of(player.page)) == pytest.approx(2.1, rel=1e-6)
    out = tmp_path / "animation"
    assert cli.main(["animate", str(FOUR_BAR), str(run_folder / "results.csv"), "-o", str(out),
                     "--no-vtk", "--set", "b=2.1"]) == 0
    assert data_of(player.page) == data_of((out / "animation.html").read_text())
    # a DataFrame of load_results, with the model given: the same page
    again = casmech.show(casmech.load_results(run_folder), casmech.load(FOUR_BAR, {"b": "2.1"}))
    assert again.page == player.page
    saved = player.save(tmp_path / "saved" / "player.html")
    assert saved.read_text(encoding="utf-8") == player.page


def test_iframe_holds_the_page(run_folder):
    player = casmech.show(run_folder, height=300)
    shown = player._repr_html_()
    source = re.fullmatch(r'<iframe srcdoc="([^"]*)" title="casmech player: four_bar" '
                          r'sandbox="allow-scripts" style="width: 100%; height: 300px; '
                          r'border: 1px solid #ccc"></iframe>', shown)
    assert source and html.unescape(source.group(1)) == player.page


@pytest.mark.parametrize("given, message", [
    (3, "expected a Result of casmech.analyze"),
    ("no/such/folder", "no such results folder or file"),
])
def test_show_refuses_what_it_cannot_draw(given, message):
    with pytest.raises(casmech.UsageError, match=message):
        casmech.show(given)


def test_show_without_a_model_file_asks_for_one(run_folder, tmp_path):
    frame = casmech.load_results(run_folder)
    frame.attrs["metadata"] = {}
    with pytest.raises(casmech.UsageError, match="pass the model"):
        casmech.show(frame)


def test_the_iframe_plays_in_a_browser(run_folder, chromium, tmp_path):  # noqa: F811
    page = tmp_path / "notebook.html"
    page.write_text("<!DOCTYPE html><html><body style='margin:0'>"
                    + casmech.show(run_folder, height=340)._repr_html_() + "</body></html>")
    shot = tmp_path / "shot.png"
    finish(browse(chromium, page.resolve().as_uri(), f"--screenshot={shot}"))
    picture = read_png(shot)[BAR:330].astype(int)
    # the three links in their palette colours (blue, red, amber): many pixels of each hue
    blue = (picture[..., 2] > picture[..., 0] + 60) & (picture[..., 2] > picture[..., 1] + 30)
    red = (picture[..., 0] > picture[..., 1] + 80) & (picture[..., 0] > picture[..., 2] + 80)
    assert blue.sum() > 20 and red.sum() > 50, (blue.sum(), red.sum())
