"""The 3D view (/view3d) in real headless chromium, drawn by WebGL in software (SwiftShader), against real runs
and a real recording: where the picture shows each body is measured in the screenshot's pixels."""

from __future__ import annotations

import io
import math
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

import simatch
from simatch.web import LiveView

from .conftest import run_until, shot, wait_frame
from .test_cli import _finish, _start, _urls
from .test_readme_screenshots import MOMENT, SHOTS, SIZE, _png_size
from .test_recordings import _recorded_at, recording  # noqa: F401  (the module's recording, a fixture)

PAD = 24  # [CSS px] the border the 2D pages leave round the floor; the top camera frames the field the same way

#: the aerial encirclement's arena with its robots still (no strategies, no scattering): ground robots, drones,
#: the ball, pillars
STILL = {
    "judge.scatter": None,
    "teams.cyan.strategy": "none",
    "teams.magenta.strategy": "none",
    "teams.cyan.squads.0.model_params.start_altitude": 1.0,  # the drones fly (and hover where they are put)
}
SPOTS = {"cyan/5": (-4.5, -2.0, 0.0, 0.5), "magenta/2": (3.5, 1.0, 0.0, 2.0), "cyan/11": (4.0, -3.5, 2.0, 0.3)}
BALL = (-3.0, 4.5)


def _cyan(px):
    r, g, b = px[..., 0].astype(int), px[..., 1].astype(int), px[..., 2].astype(int)
    return (b > 110) & (g > 90) & (r < 90) & (b > r + 60)


def _magenta(px):
    r, g, b = px[..., 0].astype(int), px[..., 1].astype(int), px[..., 2].astype(int)
    return (r > 110) & (b > 60) & (g < 80) & (r > g + 60)


def _orange(px):
    r, g, b = px[..., 0].astype(int), px[..., 1].astype(int), px[..., 2].astype(int)
    return (r > 150) & (g > 60) & (g < 190) & (b < 70) & (r > g + 50)


KINDS = {"cyan": _cyan, "magenta": _magenta, "ball": _orange}


def _screen(page) -> np.ndarray:
    """The canvas as the screenshot shows it (RGB, CSS pixels: the pages are opened at scale 1)."""
    return np.asarray(Image.open(io.BytesIO(page.locator("#scene3d").screenshot())).convert("RGB"))


def _centre(img: np.ndarray, kind: str, at: tuple[float, float], reach: float) -> tuple[float, float, int]:
    """The centre (x, y) and count of the pixels of ``kind`` within ``reach`` pixels of ``at``."""
    ys, xs = np.nonzero(KINDS[kind](img))
    keep = np.hypot(xs - at[0], ys - at[1]) <= reach
    n = int(keep.sum())
    if n == 0:
        return (math.nan, math.nan, 0)
    return (float(xs[keep].mean()), float(ys[keep].mean()), n)


def _top_framing(page) -> tuple[float, float, float]:
    """The 2D pages' framing of the canvas as it is now (centre and pixels per metre), computed here from the
    canvas's size and the field, not asked of the page."""
    field = page.evaluate("window.simatch.hello.field")
    box = page.locator("#scene3d").bounding_box()
    w, h = box["width"], box["height"]
    length, width = field["length"] + 2 * field["margin"], field["width"] + 2 * field["margin"]
    scale = min((w - 2 * PAD) / length, (h - 2 * PAD) / width)
    return (w / 2, h / 2, scale)


def _at(framing, x: float, y: float) -> tuple[float, float]:
    cx, cy, s = framing
    return (cx + x * s, cy - y * s)


def _place(sim) -> None:
    for name, (x, y, z, yaw) in SPOTS.items():
        sim.set_model_state(name, x=x, y=y, z=z, yaw=yaw)
    sim.set_model_state("ball", x=BALL[0], y=BALL[1], vx=0.0, vy=0.0)


def _assert_drawn_at(page, img, kind: str, x: float, y: float, what: str) -> None:
    framing = _top_framing(page)
    s = framing[2]
    want = _at(framing, x, y)
    got_x, got_y, n = _centre(img, kind, want, reach=0.9 * s)
    assert n > 8, f"{what}: no {kind} pixels within 0.9 m of ({x:.2f}, {y:.2f})"
    off = math.hypot(got_x - want[0], got_y - want[1]) / s
    assert off <= 0.1, f"{what}: drawn {off:.3f} m from where the simulator has it ({x:.2f}, {y:.2f})"


@pytest.fixture
def arena():
    sim = simatch.Simulation("aerial_encirclement", seed=0, overrides=STILL)
    view = LiveView(sim, port=0).start()
    yield sim, view
    view.close()
    sim.close()


def _watch_requests(page, requests: list[str]) -> None:
    """Note every address the page asks for: its requests and its WebSockets."""
    page.on("request", lambda r: requests.append(r.url))
    page.on("websocket", lambda ws: requests.append(ws.url))


def _open_3d(open_page, view, requests: list[str]):
    page = open_page("about:blank", width=1400, height=850)
    _watch_requests(page, requests)
    page.goto(view.urls["3d view"])
    return page


def _local(requests: list[str]) -> None:
    """Every request went to this machine's server (the three.js modules too: no CDN)."""
    assert any("/static/vendor/three/three.core.js" in u for u in requests), "three.js came from the server"
    assert any(u.startswith("ws://127.0.0.1:") for u in requests), "the frames came over the server's WebSocket"
    outside = [u for u in requests if not u.startswith(("http://127.0.0.1:", "ws://127.0.0.1:", "data:", "blob:"))]
    assert requests and not outside, f"requests beyond this machine: {outside}"


def test_the_3d_view_draws_each_body_where_the_simulator_has_it_and_follows_the_run(arena, open_page):
    sim, view = arena
    _place(sim)
    sim.run(seconds=0.3)
    placed_at = sim.time
    truth = sim.model_states()
    requests: list[str] = []
    page = _open_3d(open_page, view, requests)
    wait_frame(page, sim.time)
    assert page.evaluate("window.simatch.webgl") is True, "WebGL (SwiftShader) in headless chromium"
    hello = page.evaluate("window.simatch.hello")
    assert hello["role"] == "view3d"
    drone = next(r for r in hello["robots"] if r["name"] == "cyan/11")
    assert drone["body"]["kind"] == "drone" and len(drone["body"]["rotors"]) == 4
    # the top camera: every body's pixels centre within 0.1 m of its simulated place
    img = _screen(page)
    for name in SPOTS:
        _assert_drawn_at(page, img, name.split("/")[0], truth[name].x, truth[name].y, name)
    _assert_drawn_at(page, img, "ball", truth["ball"].x, truth["ball"].y, "the ball")
    assert truth["cyan/11"].z == pytest.approx(2.0, abs=0.05), "the drone hovers where it was put"
    shot(page, "view3d_top")

    # live: the run advances, the picture moves with it
    sim.set_model_state("cyan/5", x=-4.5, y=2.5, yaw=-1.0)
    sim.set_model_state("ball", x=-1.0, y=5.0)
    run_until(sim, lambda: sim.time > placed_at + 0.5)
    wait_frame(page, sim.time)
    moved = sim.model_states()
    img = _screen(page)
    _assert_drawn_at(page, img, "cyan", moved["cyan/5"].x, moved["cyan/5"].y, "cyan/5 after it moved")
    _assert_drawn_at(page, img, "ball", moved["ball"].x, moved["ball"].y, "the ball after it moved")
    framing = _top_framing(page)
    assert _centre(img, "cyan", _at(framing, -4.5, -2.0), 0.3 * framing[2])[2] == 0, "nothing left where it was"

    # looking back: pause (Space), seek to a moment before the second placement (the states published at
    # placed_at itself are those after it: they are sensed when the run goes on), then back to live (L)
    page.keyboard.press("Space")
    page.wait_for_function("!window.simatch.frame.timeline.live && !window.simatch.frame.timeline.playing")
    back = placed_at - 0.1
    page.evaluate("t => window.simatch.conn.request({type: 'timeline', action: 'seek', value: t})", back)
    page.wait_for_function(
        "t => { const tl = window.simatch.frame.timeline; return !tl.live && Math.abs(tl.t - t) < 0.02; }", arg=back
    )
    page.evaluate("() => new Promise((done) => requestAnimationFrame(() => requestAnimationFrame(done)))")
    img = _screen(page)
    shot(page, "view3d_looked_back")
    _assert_drawn_at(page, img, "cyan", truth["cyan/5"].x, truth["cyan/5"].y, "cyan/5 looked back at")
    _assert_drawn_at(page, img, "ball", truth["ball"].x, truth["ball"].y, "the ball looked back at")
    page.keyboard.press("l")
    page.wait_for_function("window.simatch.frame.timeline.live === true")
    wait_frame(page, sim.time)

    # the broadcast camera, from the side: the drone flies at its height over its shadow
    page.keyboard.press("2")
    assert page.inner_text("#camera") == "broadcast"
    page.wait_for_timeout(2500)  # the moving camera settles on the still scene
    d = moved["cyan/11"]
    up = page.evaluate("([x, y, z]) => window.simatch.view.project(x, y, z)", [d.x, d.y, d.z])
    floor = page.evaluate("([x, y]) => window.simatch.view.project(x, y, 0)", [d.x, d.y])
    assert floor[1] - up[1] > 40, f"2 m of altitude is {floor[1] - up[1]:.0f} px on the side camera"
    img = _screen(page)
    assert _centre(img, "cyan", up, 12)[2] > 5, "the drone is drawn in the air"
    assert _centre(img, "cyan", floor, 8)[2] == 0, "not on the floor"
    # ... and a ball in the air (a lob) at its height, not on the floor
    sim.set_model_state("ball", x=-1.0, y=3.0, z=1.0, vx=0.0, vy=0.0, vz=0.0)
    sim.run(seconds=0.02)
    wait_frame(page, sim.time)
    b = sim.model_states()["ball"]
    assert b.z > 0.9
    up = page.evaluate("([x, y, z]) => window.simatch.view.project(x, y, z)", [b.x, b.y, b.z])
    floor = page.evaluate("([x, y, z]) => window.simatch.view.project(x, y, z)", [b.x, b.y, 0.11])
    assert floor[1] - up[1] > 15, f"1 m of height is {floor[1] - up[1]:.0f} px on the side camera"
    img = _screen(page)
    assert _centre(img, "ball", up, 8)[2] > 5, "the ball is drawn in the air"
    assert _centre(img, "ball", floor, 5)[2] == 0, "not on the floor"
    shot(page, "view3d_broadcast")
    assert page.evaluate("window.simatch.view.contextLost") == 0, "the WebGL context was never lost"
    _local(requests)


@pytest.fixture(scope="module")
def rosbag2_folder(recording, tmp_path_factory):  # noqa: F811
    """The module's recording as a rosbag2 folder (``simatch export --format rosbag2``)."""
    folder = tmp_path_factory.mktemp("rosbag2") / "match"
    subprocess.run(
        [sys.executable, "-m", "simatch", "export", str(recording), "--format", "rosbag2", "--out", str(folder)],
        check=True,
        timeout=120,
        stdout=subprocess.DEVNULL,
    )
    return folder


@pytest.mark.parametrize("kind", ["mcap", "rosbag2"])
def test_the_3d_view_replays_a_recording_sought_to_a_moment(kind, request, browser):
    path = request.getfixturevalue("recording" if kind == "mcap" else "rosbag2_folder")
    proc = _start("replay", str(path), "--view", "--view-port", "0")
    page = browser.new_page(viewport={"width": 1400, "height": 850}, device_scale_factor=1)
    requests: list[str] = []
    _watch_requests(page, requests)
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    try:
        urls = _urls(proc)
        page.goto(urls["3d view"])
        page.wait_for_function("window.simatch && window.simatch.frame && window.simatch.frame.timeline")
        t = 1.5
        page.wait_for_function("window.simatch.frame.timeline.end >= 2.9")  # the whole recording is there to seek in
        page.evaluate("() => window.simatch.conn.request({type: 'timeline', action: 'pause'})")
        page.evaluate("t => window.simatch.conn.request({type: 'timeline', action: 'seek', value: t})", t)
        page.wait_for_function(
            "t => { const tl = window.simatch.frame.timeline;"
            " return !tl.live && !tl.playing && Math.abs(tl.t - t) < 0.02; }",
            arg=t,
        )
        page.evaluate("() => new Promise((done) => requestAnimationFrame(() => requestAnimationFrame(done)))")
        frame = page.evaluate("window.simatch.frame")
        recorded = _recorded_at(path, frame["t"])
        img = _screen(page)
        for r in frame["robots"]:
            assert (r["x"], r["y"]) == pytest.approx(recorded[r["name"]], abs=1e-3)
        for name in ("magenta/2", "magenta/4"):
            _assert_drawn_at(page, img, "magenta", *recorded[name], f"{name} at {frame['t']} s")
        shot(page, f"view3d_replay_{kind}")
        assert page.evaluate("window.simatch.view.contextLost") == 0
        _local(requests)
        assert not errors, errors
    finally:
        page.close()
        _finish(proc)


def test_without_webgl_the_page_says_so(live, open_page):
    sim, view = live()
    sim.run(seconds=0.2)
    page = open_page("about:blank")
    page.add_init_script(
        """(() => {
          const original = HTMLCanvasElement.prototype.getContext;
          HTMLCanvasElement.prototype.getContext = function (kind, ...rest) {
            return /webgl/i.test(kind) ? null : original.call(this, kind, ...rest);
          };
        })();"""
    )
    page.goto(view.urls["3d view"])
    wait_frame(page, sim.time)
    assert page.locator("#nowebgl").is_visible()
    assert "WebGL is not available" in page.inner_text("#nowebgl")
    assert page.evaluate("window.simatch.view") is None
    assert page.inner_text("#clock") != "–", "the overlay still shows the game"


@pytest.mark.slow
def test_the_readme_screenshot_of_the_3d_view(browser):
    """The README's 3D picture: the refereed match of the 2D screenshots (seed 1, one minute in), broadcast camera."""
    with simatch.Simulation("msl_5v5", seed=1) as sim:
        view = LiveView(sim, port=0).start()
        page = browser.new_page(viewport=SIZE, device_scale_factor=1)
        try:
            sim.run(seconds=MOMENT)
            page.goto(view.urls["3d view"])
            wait_frame(page, sim.time)
            page.keyboard.press("2")
            page.keyboard.press("h")  # the keys' help off: the picture only
            page.wait_for_timeout(2500)
            SHOTS.mkdir(parents=True, exist_ok=True)
            path = SHOTS / "view3d.png"
            page.screenshot(path=str(path))
            assert _png_size(path) == (SIZE["width"], SIZE["height"])
            assert page.evaluate("window.simatch.view.contextLost") == 0
        finally:
            page.close()
            view.close()


def test_the_pages_link_to_the_3d_view(live, open_page):
    sim, view = live()
    sim.run(seconds=0.2)
    token = view.access.token("view3d")
    for label in ("referee", "replay"):
        page = open_page(view.urls[label])
        wait_frame(page, sim.time)
        assert page.get_attribute("#link3d", "href") == f"/view3d?token={token}", label
    coach = open_page(view.urls["cyan coach"])
    wait_frame(coach, sim.time)
    assert coach.get_attribute("#link3d", "href") == "/view3d", "a coach sees what its team perceives, not the world"
