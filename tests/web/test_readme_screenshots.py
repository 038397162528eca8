"""The README's pictures of the web UI, made in real headless chromium from a real refereed match.

Deterministic: the same scene, seed and moment (the run is advanced to it before any page opens, so the pages
draw that moment only, with no ball trail), the same window size. The test writes them to test-artifacts/web/readme/;
``scripts/update-readme-screenshots.sh`` runs it and copies them into docs/img/, which the README shows.
"""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

from simatch.web import LiveView

from .conftest import ARTIFACTS, wait_frame

ROOT = Path(__file__).resolve().parents[2]
SHOTS = ARTIFACTS / "readme"
MOMENT = 60.0  # seed 1 at one minute: play on, a pass under way
SIZE = {"width": 1280, "height": 820}


def _png_size(path: Path) -> tuple[int, int]:
    head = path.read_bytes()[:24]
    assert head[:8] == b"\x89PNG\r\n\x1a\n"
    return struct.unpack(">II", head[16:24])


@pytest.mark.slow
def test_the_readme_screenshots_of_the_referee_console_and_a_coach_page(browser):
    import simatch

    with simatch.Simulation("msl_5v5", seed=1) as sim:
        view = LiveView(sim, port=0).start()
        pages = []
        try:
            sim.run(seconds=MOMENT)  # before any page opens: at full speed, and the pages see this moment only
            SHOTS.mkdir(parents=True, exist_ok=True)
            for label, name in (("referee", "referee-console"), ("cyan coach", "coach-page")):
                page = browser.new_page(viewport=SIZE, device_scale_factor=1)
                pages.append(page)
                page.goto(view.urls[label])
                wait_frame(page, sim.time)
                page.wait_for_function("document.querySelectorAll('#events li').length > 3")
                if label == "referee":
                    assert page.inner_text("#stage") == "first_half" and page.inner_text("#clock") == "1:00.0"
                else:
                    assert "magenta as cyan sees them" in page.inner_text("#legend")
                    roles = page.locator("#robots tbody td:nth-child(2)").all_inner_texts()
                    assert "goalkeeper" in roles and not any(r.isupper() for r in roles), roles
                page.evaluate("document.activeElement && document.activeElement.blur()")
                path = SHOTS / f"{name}.png"
                page.screenshot(path=str(path))
                assert _png_size(path) == (SIZE["width"], SIZE["height"])
                assert path.stat().st_size < 400_000, "a small PNG"
        finally:
            for page in pages:
                page.close()
            view.close()


def test_the_readme_shows_the_screenshots_it_has():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    first_screen = readme[: readme.index("## What is here")]
    for name in ("referee-console", "coach-page", "view3d"):  # view3d: tests/web/test_view3d.py
        assert f"docs/img/{name}.png" in first_screen
        path = ROOT / "docs" / "img" / f"{name}.png"
        assert path.exists() and _png_size(path) == (SIZE["width"], SIZE["height"])
