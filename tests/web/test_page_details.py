"""What a new user trips on in the pages (issue 21), each in real headless chromium against a real run."""

from __future__ import annotations

from .conftest import shot, wait_frame

CLOCK = """async (times) => {
  const m = await import("/static/simatch.js");
  return times.map((t) => m.clock(t));
}"""


#: simulated seconds -> what every page's clock shows (the edges of the tenth and of the minute)
CLOCK_EDGES = {
    0.0: "0:00.0",
    0.04: "0:00.0",
    9.96: "0:10.0",
    59.94: "0:59.9",
    59.95: "1:00.0",
    59.97: "1:00.0",
    59.99: "1:00.0",
    60.0: "1:00.0",
    61.25: "1:01.3",
    119.95: "2:00.0",
    119.97: "2:00.0",
    120.0: "2:00.0",
    599.96: "10:00.0",
    1810.0: "30:10.0",
}


def test_the_clock_never_shows_sixty_seconds(live, open_page):
    """A 120 s recording ends at "2:00.0", not "1:60.0": the seconds are rounded before the minutes are split."""
    _, view = live()
    page = open_page(view.urls["replay"])
    shown = page.evaluate(CLOCK, list(CLOCK_EDGES))
    assert dict(zip(CLOCK_EDGES, shown)) == CLOCK_EDGES
    assert page.evaluate(CLOCK, [None]) == ["–"]
    # no time of a whole match shows 60 seconds
    times = [60 * m + frac for m in range(31) for frac in (59.949, 59.95, 59.951, 59.97, 59.99, 59.999)]
    assert not [(t, c) for t, c in zip(times, page.evaluate(CLOCK, times)) if ":60" in c]


def test_a_page_opened_with_a_wrong_token_disables_its_controls(live, open_page):
    sim, view = live()
    sim.run(seconds=0.1)
    for path in ("/coach/cyan", "/referee", "/replay"):
        page = open_page(view.server.base_url + f"{path}?token=not-a-token")
        page.wait_for_function("document.getElementById('conn').textContent === 'refused'")
        assert page.locator("#toast").is_visible() and "unknown or missing token" in page.inner_text("#toast")
        controls = page.locator("button, input, select")
        assert controls.count() > 3
        enabled = page.evaluate(
            "[...document.querySelectorAll('button, input, select')].filter((e) => !e.disabled).map((e) => e.id)"
        )
        assert enabled == [], f"{path}: still active after the refusal: {enabled}"
        shot(page, f"refused{path.replace('/', '_')}")
    # a good token on the same server is unaffected
    good = open_page(view.urls["cyan coach"])
    wait_frame(good, sim.time)
    assert good.locator("#optpass").is_enabled()
