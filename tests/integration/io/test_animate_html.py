"""casmech animate, HTML side: the page is self-contained, holds the table's poses, and plays in
headless Chromium (screenshots at two times differ, the status line reports a drawn frame, no
console output at all).

Chromium: `apt-get install -y chromium`. Without it these browser tests skip, except when the
environment variable CI is set: then they fail (CI must exercise the player).
"""

import json
import os
import re
import shutil
import subprocess
import tempfile

import numpy as np
import pytest
from PIL import Image

from casmech import cli
from tests.unit.io.test_animate import BODIES, TIMES, make_case

# WebGL through SwiftShader, Chromium's software renderer (no GPU on CI machines)
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
         "--enable-logging=stderr", "--v=0", "--window-size=480,360"]
BACKGROUND = (0xEE, 0xF1, 0xF5)  # the scene's background colour in player.js
BAR = 41  # pixel rows of the control bar above the canvas (40 px + border)
XHTML = "http://www.w3.org/1999/xhtml"  # a namespace name three.js creates elements in


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    folder = tmp_path_factory.mktemp("html")
    model, results, r, q = make_case(folder)
    out = folder / "out"
    assert cli.main(["animate", str(model), str(results), "-o", str(out), "--no-vtk"]) == 0
    return out / "animation.html", r, q


def page_data(path):
    match = re.search(r'<script type="application/json" id="casmech-data">(.*?)</script>',
                      path.read_text(), re.S)
    return json.loads(match.group(1))


def test_page_needs_no_network(page):
    text = page[0].read_text()
    assert "default-src 'none'" in text  # the page's CSP forbids every fetch
    assert not re.search(r"\b(src|href)\s*=", text, re.I)  # no external script, style or image
    assert not re.search(r"https?://|//cdn|@import", text.replace(XHTML, ""), re.I)
    style = re.search(r"<style>(.*?)</style>", text, re.S).group(1)
    assert "url(" not in style.lower()  # no image or font the style would fetch
    # the data, three.js and the player: three scripts, none ended early
    assert "<\\/script" not in text and text.count("</script>") == 3
    assert "var THREE=" in text  # three.js is inlined


def test_page_holds_the_tables_poses(page):
    path, r, q = page
    data = page_data(path)
    assert data["bodies"] == BODIES
    # the page keeps 7 significant digits: relative 5e-7 of each number
    np.testing.assert_allclose(data["times"], TIMES, rtol=5e-7, atol=1e-300)
    np.testing.assert_allclose(np.reshape(data["r"], r.shape), r, rtol=5e-7, atol=1e-12)
    np.testing.assert_allclose(np.reshape(data["p"], q.shape), q, rtol=5e-7, atol=1e-12)
    # one part per body (all have one shape or the default), one marker per joint point
    assert [part["body"] for part in data["parts"] if part["joint"] < 0] == [0, 1, 2, 3, 4]
    assert len(data["parts"]) == 5 + 8


# ---------------------------------------------------------------------------------- browser
@pytest.fixture(scope="module")
def chromium():
    found = shutil.which("chromium")
    if found is None:
        message = "chromium is not installed (apt-get install -y chromium)"
        if os.environ.get("CI"):
            pytest.fail(message + "; CI must run the HTML player test")
        pytest.skip(message)
    return found


def read_png(path):
    """A PNG screenshot -> (height, width, 3) uint8 RGB array (decoded by Pillow)."""
    with Image.open(path) as image:
        assert image.format == "PNG"
        return np.asarray(image.convert("RGB"))


def browse(chromium, url, *action):
    """Start one headless Chromium on url with an action (--screenshot=... or --dump-dom)."""
    profile = tempfile.mkdtemp(prefix="casmech-chromium-")
    process = subprocess.Popen([chromium, *FLAGS, f"--user-data-dir={profile}", *action, url],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    return process, profile


def finish(job):
    process, profile = job
    try:
        out, err = process.communicate(timeout=60)
    finally:
        shutil.rmtree(profile, ignore_errors=True)
    assert process.returncode == 0, err[-2000:]
    # Chromium reports its GL driver's performance notes (the screenshot's read-back) as console
    # lines of the page; anything else there is the page's own output
    console = [line for line in err.splitlines()
               if ":CONSOLE" in line and "GL Driver Message" not in line]
    assert not console, "the page wrote to the console:\n" + "\n".join(console)
    return out


def status(dom):
    """The player's status line (filled by player.js after every drawn frame), parsed."""
    text = re.search(r'<output id="status"[^>]*>(.*?)</output>', dom, re.S).group(1)
    match = re.fullmatch(r"ok frame=(\d+) of (\d+) t=(\S+) triangles=(\d+) shown=(\d+)", text)
    assert match, text
    return match


def test_player_draws_frames_that_change_with_time(page, chromium, tmp_path):
    url = page[0].resolve().as_uri()
    shots = {t: tmp_path / f"t{t}.png" for t in ("0", "0.3")}
    jobs = [browse(chromium, f"{url}#t={t}", f"--screenshot={shot}") for t, shot in shots.items()]
    jobs.append(browse(chromium, f"{url}#t=0.29", "--dump-dom"))
    jobs.append(browse(chromium, url, "--virtual-time-budget=2000", "--dump-dom"))
    finish(jobs[0]), finish(jobs[1])
    match = status(finish(jobs[2]))
    assert (int(match[1]), int(match[2])) == (3, len(TIMES))  # 0.29 s is nearest row 3 (0.3 s)
    assert float(match[3]) == pytest.approx(0.3, rel=1e-12, abs=0)  # the row's own time
    assert int(match[4]) > 100  # triangles of the five bodies drawn (some may face away)

    # without #t the page plays at 1x and loops: 2 s of (virtual) page time run the 0.5 s,
    # 6-row table 4 times, so it draws between one loop (6) and 5 loops' worth (1 + 30) of frames
    played = status(finish(jobs[3]))
    assert 6 <= int(played[5]) <= 31, played[0]

    pictures = [read_png(shot) for shot in shots.values()]
    for picture in pictures:  # the decoder reads the page's known colours where nothing is drawn
        assert tuple(picture[2, 2]) == (255, 255, 255)  # the control bar
    pictures = [picture[BAR:] for picture in pictures]
    for picture in pictures:  # the view is not empty: many pixels differ from its background
        drawn = np.any(picture != BACKGROUND, axis=-1)
        assert drawn.sum() > 500
    changed = np.any(pictures[0] != pictures[1], axis=-1)
    assert changed.sum() > 500  # the bodies moved between t = 0 and t = 0.3
