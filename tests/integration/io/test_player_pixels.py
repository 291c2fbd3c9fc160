"""The three.js player's pixels in headless Chromium (WebGL on SwiftShader): with the camera put
at a known place through the URL (`#view=`), a pinhole projection computed here says where each
ball's centre, the ground and the sky must appear, and the screenshot must show each body's
colour there at the asked time (and no longer where it was), the ground below, the background
above the horizon and the shadow of a ball where the light's direction puts it.

Chromium: `apt-get install -y chromium`; without it these tests skip, except under CI.
"""

import numpy as np
import pytest

from casmech import cli
from tests.integration.io.test_animate_html import (  # noqa: F401 - chromium is a fixture
    BAR,
    browse,
    chromium,
    finish,
    read_png,
    status,
)

MODEL = """\
casmech: 1
name: two_balls
gravity: [0, 0, -9.81]
bodies:
  - {name: blue, mass: 1, inertia: [0.004, 0.004, 0.004], position: [-0.5, 0, 0.3],
     geometry: [{sphere: 0.1}]}
  - {name: red, mass: 1, inertia: [0.004, 0.004, 0.004], position: [0.5, 0, 0.3],
     geometry: [{sphere: 0.1}]}
forces:
  - {name: floor, type: sphere_plane, body_i: ground, body_j: blue,
     plane: {at: [0, 0, 0], normal: [0, 0, 1]}, normal: {law: linear, stiffness: 1.0e5}}
"""
TIMES = np.array([0.0, 0.5, 1.0])
# blue rolls along x from -0.5 to 0.5, red rises from 0.3 to 0.5
BLUE = np.column_stack([-0.5 + TIMES, 0 * TIMES, 0.3 + 0 * TIMES])
RED = np.column_stack([0.5 + 0 * TIMES, 0 * TIMES, 0.3 + 0.2 * TIMES])
WIDTH, HEIGHT = 480, 360  # test_animate_html's window; the 3D view is below the 40 px bar
EYE, TARGET = np.array([0.0, -3.0, 0.9]), np.array([0.0, 0.0, 0.3])
FOV = 40.0  # player.js: the camera's vertical field of view, degrees
SUN = np.array([1.0, 0.6, 4.0])  # player.js: towards the light (across x, across2 y, up z)
BLUE_RGB, RED_RGB = (0x42, 0x85, 0xF4), (0xDB, 0x44, 0x37)  # player.js PALETTE[0], [1]


def project(point):
    """Pixel (column, row) of a global point in the screenshot: a pinhole camera at EYE looking
    at TARGET with z up, FOV vertically over the view's height."""
    forward = (TARGET - EYE) / np.linalg.norm(TARGET - EYE)
    right = np.cross(forward, [0, 0, 1.0])
    right /= np.linalg.norm(right)
    upward = np.cross(right, forward)
    d = np.asarray(point, float) - EYE
    depth = d @ forward
    height = HEIGHT - 40
    focal = height / 2 / np.tan(np.radians(FOV) / 2)
    column = WIDTH / 2 + focal * (d @ right) / depth
    row = 40 + height / 2 - focal * (d @ upward) / depth
    return int(round(column)), int(round(row))


def colour(picture, point, size=2):
    """The median colour of a small square of pixels around a point's projection."""
    column, row = project(point)
    patch = picture[row - size:row + size + 1, column - size:column + size + 1].reshape(-1, 3)
    return np.median(patch.astype(float), axis=0)


def hue_of(rgb, reference):
    """Whether a shaded colour is the reference colour lit more or less: its channels in the
    same order and proportions (each within 0.12 of the reference's share of the sum)."""
    rgb, reference = np.asarray(rgb, float), np.asarray(reference, float)
    return np.all(np.abs(rgb / rgb.sum() - reference / reference.sum()) < 0.12)


def grey(rgb):
    return np.ptp(np.asarray(rgb, float)) < 16


@pytest.fixture(scope="module")
def shots(tmp_path_factory, chromium):  # noqa: F811 - the fixture imported above
    folder = tmp_path_factory.mktemp("pixels")
    (folder / "two_balls.yaml").write_text(MODEL)
    names = ["t"] + [f"{b}.{c}" for b in ("blue", "red")
                     for c in ("x", "y", "z", "e0", "e1", "e2", "e3")]
    unit = np.tile([1.0, 0, 0, 0], (len(TIMES), 1))
    values = np.column_stack([TIMES, BLUE, unit, RED, unit])
    with open(folder / "results.csv", "w") as handle:
        handle.write(",".join(names) + "\n")
        np.savetxt(handle, values, delimiter=",", fmt="%.17g")
    out = folder / "out"
    assert cli.main(["animate", str(folder / "two_balls.yaml"), str(folder / "results.csv"),
                     "-o", str(out), "--no-vtk"]) == 0
    url = (out / "animation.html").resolve().as_uri()
    view = ",".join(f"{x:g}" for x in (*EYE, *TARGET))
    pictures = {t: folder / f"t{t}.png" for t in ("0.5", "1")}
    jobs = [browse(chromium, f"{url}#t={t}&view={view}", f"--screenshot={path}")
            for t, path in pictures.items()]
    jobs.append(browse(chromium, f"{url}#t=0.5&view={view}", "--dump-dom"))
    for job in jobs[:2]:
        finish(job)
    drawn = status(finish(jobs[2]))
    return {t: read_png(path) for t, path in pictures.items()}, drawn


def test_each_ball_is_drawn_in_its_colour_where_it_is(shots):
    pictures, drawn = shots
    assert int(drawn[1]) == 1  # frame 1, t = 0.5
    at_half = pictures["0.5"]
    assert at_half.shape == (HEIGHT, WIDTH, 3)
    assert hue_of(colour(at_half, BLUE[1]), BLUE_RGB), colour(at_half, BLUE[1])
    assert hue_of(colour(at_half, RED[1]), RED_RGB), colour(at_half, RED[1])
    at_end = pictures["1"]
    assert hue_of(colour(at_end, BLUE[2]), BLUE_RGB), colour(at_end, BLUE[2])
    assert hue_of(colour(at_end, RED[2]), RED_RGB), colour(at_end, RED[2])
    # where the blue ball was at t = 0.5 is no longer blue at t = 1 (the ground shows there)
    assert not hue_of(colour(at_end, BLUE[1]), BLUE_RGB)
    assert grey(colour(at_end, BLUE[1] - [0, 0, 0.3]))


def test_ground_below_and_background_above_the_horizon(shots):
    pictures, _ = shots
    picture = pictures["0.5"]
    background = np.array([0xEE, 0xF1, 0xF5], float)
    for point in ([-1.0, 1.0, 0.0], [1.0, 1.5, 0.0], [0.0, -1.0, 0.0]):  # on the plane z = 0
        ground = colour(picture, point)
        assert grey(ground) and 120 < ground.mean() < 250, (point, ground)
        assert np.abs(ground - background).max() > 4, (point, ground)  # not the sky
    sky = colour(picture, [0.0, 40.0, 6.0])  # far beyond the ground plane, high up
    np.testing.assert_allclose(sky, background, rtol=0, atol=1)  # 8-bit rounding


def test_a_ball_casts_its_shadow_where_the_light_puts_it(shots):
    pictures, _ = shots
    picture = pictures["0.5"]
    # the light shines along -SUN: the red ball's centre falls on z = 0 at c - c_z / 4 SUN
    shadow = RED[1] - RED[1][2] / SUN[2] * SUN
    lit = shadow + [0.6, 0.6, 0]  # ground away from both balls and their shadows
    dark, bright = colour(picture, shadow), colour(picture, lit)
    assert grey(dark) and grey(bright)
    assert dark.mean() < bright.mean() - 25, (dark, bright)
    column, row = project(shadow)
    assert row > BAR  # the shadow is in the view
