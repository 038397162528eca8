"""Browser tests of the web UI: real runs, a real server, Debian's chromium driven by Playwright.

The run stays in the test's thread: a test acts in the page, then advances the simulation until the
effect shows (`run_until`), so nothing races. Screenshots go to test-artifacts/web/ (ignored by git). The browser
(``browser``) is the session's one, in tests/conftest.py.
"""

from __future__ import annotations

import time
from pathlib import Path

import pytest

import simatch
from simatch.web import LiveView

ARTIFACTS = Path(__file__).resolve().parents[2] / "test-artifacts" / "web"


@pytest.fixture
def live():
    """``live(**overrides)``: a Simulation of msl_5v5 with the web UI on a free loopback port; a coach per team
    and no referee, unless the overrides name a judge."""
    made = []

    def make(scene: str = "msl_5v5", seed: int = 0, **overrides):
        if scene == "msl_5v5":
            overrides = {"judge.kind": "none", **overrides}
        sim = simatch.Simulation(scene, seed=seed, overrides=overrides)
        view = LiveView(sim, port=0).start()
        made.append((sim, view))
        return sim, view

    yield make
    for sim, view in made:
        view.close()
        sim.close()


@pytest.fixture
def open_page(browser, request):
    """``open_page(url)``: a new page that has received its first frame; page errors fail the test."""
    pages = []
    errors: list[str] = []

    def make(url: str, width: int = 1400, height: int = 850):
        page = browser.new_page(viewport={"width": width, "height": height})
        page.on("pageerror", lambda exc: errors.append(str(exc)))
        page.goto(url)
        pages.append(page)
        return page

    yield make
    for page in pages:
        page.close()
    assert not errors, f"errors in the page: {errors}"


def shot(page, name: str) -> Path:
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    path = ARTIFACTS / f"{name}.png"
    page.screenshot(path=str(path))
    return path


def run_until(sim, condition, timeout: float = 10.0, chunk: float = 0.05) -> None:
    """Advance the run in small chunks until ``condition()`` holds (wall-clock ``timeout``)."""
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(
                f"the condition did not come true in time (t={sim.time:.3f}, pace {sim.pace}; last events: "
                f"{sim.events[-4:]})"
            )
        sim.run(seconds=chunk)


def wait_frame(page, sim_time: float, timeout: float = 10_000) -> None:
    """Wait until the page shows the world at ``sim_time`` (or later): the frame has come and the canvas has
    been drawn since (the field view draws at the next animation frame; a resize in between clears the
    canvas until then: a fresh-clone CI run once read a pixel of the cleared canvas)."""
    page.wait_for_function(
        "t => window.simatch && window.simatch.frame && window.simatch.frame.t >= t",
        arg=round(sim_time - 0.02, 3),
        timeout=timeout,
    )
    page.evaluate("() => new Promise((done) => requestAnimationFrame(() => requestAnimationFrame(done)))")


def drag_ball(page, sim, x: float, y: float) -> None:
    """Drag the ball on the page's field from where the simulator has it to (x, y), with the mouse."""
    ball = sim.model_states()["ball"]
    wait_frame(page, sim.time)  # the page shows the present (nothing moves on it any more)
    page.wait_for_function(
        "([x, y]) => { const b = window.simatch.frame && window.simatch.frame.ball;"
        " return b && Math.hypot(b.x - x, b.y - y) < 0.05; }",
        arg=[ball.x, ball.y],
    )
    a = page.evaluate("([x, y]) => window.simatch.view.toScreen(x, y)", [ball.x, ball.y])
    b = page.evaluate("([x, y]) => window.simatch.view.toScreen(x, y)", [x, y])
    box = page.locator("#field").bounding_box()
    page.mouse.move(box["x"] + a[0], box["y"] + a[1])
    page.mouse.down()
    page.mouse.move(box["x"] + (a[0] + b[0]) / 2, box["y"] + (a[1] + b[1]) / 2, steps=5)
    page.mouse.move(box["x"] + b[0], box["y"] + b[1], steps=5)
    page.mouse.up()


def start_request(page, message: dict) -> None:
    """Send ``message`` from the page without waiting (the run must step for the answer to come); the answer
    lands in ``window.answer`` ("ok" or the error's text), read it with `answer`."""
    page.evaluate(
        """m => { window.answer = null;
        window.simatch.conn.request(m).then(
            () => { window.answer = "ok"; }, (e) => { window.answer = e.message; }); }""",
        message,
    )


def answer(page):
    return page.evaluate("window.answer")
