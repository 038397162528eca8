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


def test_the_coach_page_draws_opponents_in_their_colour_with_a_legend_and_roles_in_words(live, open_page):
    sim, view = live(**{"teams.magenta.strategy": "none"})  # cyan plays nubot (roles), magenta stands
    sim.set_model_state("magenta/3", x=-3.0, y=3.0)  # in front of cyan's robots: every one of them sees it
    sim.coaches["cyan"].start_play()
    sim.run(seconds=0.5)
    page = open_page(view.urls["cyan coach"])
    wait_frame(page, sim.time)
    legend = page.inner_text("#legend")
    assert "cyan (ours)" in legend and "magenta as cyan sees them" in legend
    swatch = page.evaluate("getComputedStyle(document.querySelectorAll('#legend .swatch')[1]).borderTopColor")
    assert swatch == "rgb(224, 53, 156)", swatch
    # the opponent as cyan's perception has it: magenta over the green field, not the pale blue of before
    seen = page.evaluate("window.simatch.frame.obstacles")
    x, y, _ = next(iter(seen.values()))[0]
    r, g, b = page.evaluate(
        """([x, y]) => { const v = window.simatch.view, dpr = window.devicePixelRatio || 1;
           const [px, py] = v.toScreen(x, y);
           return [...v.ctx.getImageData(Math.round(px * dpr), Math.round(py * dpr), 1, 1).data].slice(0, 3); }""",
        [x, y],
    )
    assert r > g + 40 and r > b, (r, g, b)
    # roles and actions in words
    page.wait_for_function("window.simatch.frame.robots.every((r) => r.role)")
    roles = page.locator("#robots tbody td:nth-child(2)").all_inner_texts()
    actions = page.locator("#robots tbody td:nth-child(3)").all_inner_texts()
    assert "goalkeeper" in roles, roles
    assert not [w for w in roles + actions if "_" in w or (w.isupper() and len(w) > 1)], (roles, actions)
    shot(page, "coach_opponents_legend")


def test_robot_labels_keep_clear_of_the_ball(live, open_page):
    """A label's first place (the id above right of the robot) holds the ball: the label goes elsewhere."""
    sim, view = live(**{"teams.cyan.strategy": "startpose", "teams.magenta.strategy": "none"})
    sim.coaches["cyan"].start_play()
    sim.run(seconds=1.0)
    page = open_page(view.urls["cyan coach"])
    wait_frame(page, sim.time)
    s = sim.model_states()["cyan/4"]
    # the world point at the middle of the id's first place, from the page's own scale
    bx, by = page.evaluate(
        """([x, y]) => { const v = window.simatch.view, rad = Math.max(4, 0.25 * v.scale);
           const [sx, sy] = v.toScreen(x, y);
           return v.toWorld(sx + rad * 0.8 + 4, sy - rad * 0.8 - 6); }""",
        [s.x, s.y],
    )
    sim.set_model_state("ball", x=bx, y=by, vx=0.0, vy=0.0)
    sim.run(seconds=0.3)
    wait_frame(page, sim.time)
    page.wait_for_function("window.simatch.view.labels.some((l) => l.text === '4') && window.simatch.view.ballSpot")
    labels, spot = page.evaluate("[window.simatch.view.labels, window.simatch.view.ballSpot]")
    assert any(lab["text"] == "4" for lab in labels)
    for lab in labels:
        nx = max(lab["x"], min(spot["x"], lab["x"] + lab["w"]))
        ny = max(lab["y"], min(spot["y"], lab["y"] + lab["h"]))
        assert ((spot["x"] - nx) ** 2 + (spot["y"] - ny) ** 2) ** 0.5 > spot["r"], f"{lab} covers the ball"
    shot(page, "labels_clear_of_the_ball")


def test_a_game_without_set_pieces_shows_none_and_every_label_fits(live, open_page):
    """An encirclement: no kick-off or test buttons on the coach page or the console (its judge has no set
    pieces), no "no role" under robots whose strategy names none, and the ids of the robots at the field's
    edge stay on the canvas."""
    sim, view = live("encirclement_9v7")
    sim.run(seconds=1.0)
    coach = open_page(view.urls["cyan coach"])
    wait_frame(coach, sim.time)
    assert coach.evaluate("window.simatch.hello.set_pieces") is False
    for sel in ("#setpieces", "#testarea", "button[data-cmd='DROPBALL']"):
        assert not coach.locator(sel).is_visible(), sel
    assert coach.locator("#start").is_visible() and coach.locator("#park").is_visible()
    coach.wait_for_function("window.simatch.view.labels.length >= 9")
    labels, w, h = coach.evaluate("[window.simatch.view.labels, window.simatch.view.w, window.simatch.view.h]")
    assert {lab["text"] for lab in labels} >= {str(i) for i in range(1, 10)}
    assert not [lab for lab in labels if "role" in lab["text"]], labels
    out = [lab for lab in labels if lab["x"] < 0 or lab["y"] < 0 or lab["x"] + lab["w"] > w or lab["y"] + lab["h"] > h]
    assert out == [], f"labels cut at the canvas edge: {out}"
    shot(coach, "coach_encirclement")
    console = open_page(view.urls["referee"])
    wait_frame(console, sim.time)
    assert not console.locator("#setpieces").is_visible()
    assert not console.locator("button[data-cmd='DROPBALL']").is_visible()
    shot(console, "console_encirclement")


def test_a_match_keeps_its_set_pieces(live, open_page):
    sim, view = live(**{"judge.kind": "msl_referee"})
    sim.run(seconds=0.2)
    for url in (view.urls["cyan coach"], view.urls["referee"]):
        page = open_page(url)
        wait_frame(page, sim.time)
        assert page.evaluate("window.simatch.hello.set_pieces") is True
        assert page.locator("#setpieces button").count() == 12 and page.locator("#setpieces").is_visible()


def test_the_console_robot_list_scrolls_and_the_top_bar_cuts_nothing(live, open_page):
    sim, view = live(**{"judge.kind": "msl_referee"})
    sim.run(seconds=1.0)  # a stoppage: "STOPROBOT, next KICKOFF cyan"
    page = open_page(view.urls["referee"], width=1100, height=700)
    wait_frame(page, sim.time)
    assert page.inner_text("#command") == "STOPROBOT, next KICKOFF cyan"
    # nothing in the top bar is cut or hidden: every item lies inside the window, whole
    cut = page.evaluate(
        """[...document.querySelectorAll('header > *')].filter((e) => {
             const r = e.getBoundingClientRect();
             return r.width > 0 && (r.right > innerWidth + 0.5 || e.scrollWidth > e.clientWidth + 1);
           }).map((e) => e.id || e.className)"""
    )
    assert cut == [], cut
    # the robot list scrolls in its own box: its last robot can be reached, the page itself does not scroll
    box = page.locator("#robots-list")
    assert page.evaluate("(e) => e.scrollHeight > e.clientHeight", box.element_handle())
    box.evaluate("(e) => { e.scrollTop = e.scrollHeight; }")
    last = page.locator("#robots-table tr[data-robot='magenta/5']").bounding_box()
    frame = box.bounding_box()
    assert frame["y"] <= last["y"] and last["y"] + last["height"] <= frame["y"] + frame["height"] + 1
    assert page.evaluate("document.scrollingElement.scrollHeight <= innerHeight")
    page.locator("#robots-table tr[data-robot='magenta/5'] button.sendoff").click(trial=True)
    shot(page, "console_small_window")
