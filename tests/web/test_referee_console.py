"""The referee console in real chromium against a refereed run: every button is a request to the automatic
referee (its operator interface on the bus), which carries it out, logs it and reports it back."""

from __future__ import annotations

import math

import pytest

from .conftest import answer, drag_ball, run_until, shot, start_request, wait_frame

#: a refereed msl_5v5 whose robots stand still (so only what the test does happens)
REFEREED = {"judge.kind": "msl_referee", "teams.cyan.strategy": "none", "teams.magenta.strategy": "none"}


def operator_events(sim, since: int = 0) -> list[str]:
    return [e["detail"] for e in sim.events[since:] if e["type"] == "operator"]


def test_a_goal_shows_in_the_referee_console(live, open_page):
    sim, view = live(**REFEREED)
    sim.run(seconds=0.1)
    page = open_page(view.urls["referee"])
    wait_frame(page, sim.time)
    # the operator starts play at once (the ball is in play) and drags the ball into magenta's half
    page.click("#start")
    run_until(sim, lambda: sim.game["phase"] == "play")
    drag_ball(page, sim, 7.3, 0.8)
    run_until(sim, lambda: math.hypot(sim.model_states()["ball"].x - 7.3, sim.model_states()["ball"].y - 0.8) < 0.1)
    # cyan/4 comes up behind the ball, takes it and shoots past magenta's goalkeeper into the goal
    ball = sim.model_states()["ball"]
    sim.set_model_state("cyan/4", x=ball.x - 0.3, y=ball.y, yaw=0.0)
    sim.take_control("cyan/4")
    sim.send_action("cyan/4", dribble=True)
    sim.run(seconds=0.5)
    sim.send_action("cyan/4", kick=6.0)
    run_until(sim, lambda: sim.game["score"]["cyan"] == 1)
    goal = [e for e in sim.events if e["type"] == "goal"]
    assert len(goal) == 1 and goal[0]["team"] == "cyan" and goal[0]["robot"] == 4, goal
    sim.run(seconds=0.2)
    wait_frame(page, sim.time)
    page.wait_for_function("document.querySelector('.scoreboard .score').textContent.trim() === '1 : 0'")
    item = page.locator("#events li.goal")
    item.wait_for()
    text = item.inner_text()
    assert "goal for cyan by cyan/4" in text and "between the posts, under the bar" in text
    assert page.inner_text("#stage") == "first_half"
    assert "kick-off for magenta" in page.inner_text("#reason")
    shot(page, "goal_in_console")


def test_the_console_is_the_referees_operator(live, open_page):
    sim, view = live(**REFEREED)
    sim.run(seconds=0.1)
    page = open_page(view.urls["referee"])
    coach = open_page(view.urls["cyan coach"])
    for p in (page, coach):
        wait_frame(p, sim.time)
    # with a referee, a coach page only watches
    assert coach.locator("#start").is_disabled() and "referee gives the commands" in coach.inner_text("#cmdnote")
    assert "the referee's operator" in page.inner_text("#mode-note")

    # pause: the referee's pause (the clock stands still), then resume
    page.click("#pause")
    run_until(sim, lambda: sim.game["paused"])
    clock = sim.game["clock"]
    sim.run(seconds=0.5)
    assert sim.game["clock"] == clock and sim.game["phase"] == "paused"
    wait_frame(page, sim.time)
    page.wait_for_selector("#phase.paused")
    assert page.locator("#resume").is_enabled()
    shot(page, "referee_paused")
    page.click("#resume")
    run_until(sim, lambda: not sim.game["paused"])

    # automatic judging off (manual mode) and on again
    page.click("#auto")
    run_until(sim, lambda: sim.game["manual"])
    sim.run(seconds=0.2)  # a frame after the change (wait_frame also takes one from 20 ms before it)
    wait_frame(page, sim.time)
    page.wait_for_function("document.getElementById('auto').textContent === 'off (manual)'")
    page.click("#auto")
    run_until(sim, lambda: not sim.game["manual"])

    # dragging the ball places it: the referee's operator action
    drag_ball(page, sim, 4.0, -3.0)
    run_until(sim, lambda: math.hypot(sim.model_states()["ball"].x - 4.0, sim.model_states()["ball"].y + 3.0) < 0.1)
    assert any(e["type"] == "ball_placed" and e.get("detail") == "the operator placed the ball" for e in sim.events)

    # send a robot off: the referee parks it outside the field and disables it; a card; bring it back
    page.click("#robots-table tr[data-robot='cyan/3'] button.sendoff")
    run_until(sim, lambda: "cyan/3" in sim.game["sent_off"])
    assert sim.model_states()["cyan/3"].y < -7.0
    page.click("#robots-table tr[data-robot='magenta/2'] button.yellow")
    run_until(sim, lambda: sim.game["yellow_cards"]["magenta"] == 1)
    sim.run(seconds=0.2)
    wait_frame(page, sim.time)
    page.wait_for_selector("#robots-table tr.off[data-robot='cyan/3']")
    page.wait_for_function(
        "document.querySelector(\"#robots-table tr[data-robot='magenta/2'] .cards\").textContent.includes('1 Y')"
    )
    page.locator("#events li.send_off").wait_for()
    shot(page, "referee_sent_off_and_card")
    page.click("#robots-table tr[data-robot='cyan/3'] button.sendoff")
    run_until(sim, lambda: "cyan/3" not in sim.game["sent_off"])
    assert abs(sim.model_states()["cyan/3"].y) < 7.0

    ops = operator_events(sim)
    assert all(" (by web console #" in d for d in ops), ops
    kinds = [d.split(" (by ")[0] for d in ops]
    assert kinds[:4] == ["pause", "resume", "automatic judging off (manual mode)", "automatic judging on"], kinds
    assert kinds[4].startswith("place the ball at (4.0") or kinds[4].startswith("place the ball at (3.9"), kinds
    assert kinds[5:] == ["send cyan/3 off until returned", "yellow card for magenta/2", "bring cyan/3 back"], kinds

    # a request the referee refuses comes back to the page with its reason, and changes nothing
    start_request(page, {"type": "send_off", "robot": "cyan/2", "off": False})
    run_until(sim, lambda: answer(page) is not None)
    assert answer(page) == "the referee refused: cyan/2 is not sent off"
    assert sim.events[-1]["type"] == "operator_refused"


def test_the_pages_show_the_teams_change_ends_at_half_time(live, open_page):
    """Before half time cyan defends the goal at -x (left); after it, the right one: the goals change colours on
    the console and the coach page, their arrows turn, and the coach page turns its team's perception back to
    the world frame with the new side (cyan's goalkeeper is drawn at +10.5, where it stands)."""
    from .test_pages import PIXEL_AT, TEAM_RGB, near

    sim, view = live(**REFEREED, **{"match.half_duration": 1.0, "match.half_time": 0.5})
    sim.run(seconds=0.2)
    console, coach = open_page(view.urls["referee"]), open_page(view.urls["cyan coach"])

    def goal_colour(page, side: int):
        return page.evaluate(PIXEL_AT, [side * (11.0 + 0.6), 0.0, 0.0, 0.0])

    for page in (console, coach):
        wait_frame(page, sim.time)
        assert near(goal_colour(page, -1), TEAM_RGB["cyan"]) and near(goal_colour(page, 1), TEAM_RGB["magenta"])
    assert console.inner_text("#ends") == "cyan → · magenta ←" and coach.inner_text("#attacks") == "→"
    run_until(sim, lambda: sim.game["stage"] == "second_half")
    sim.run(seconds=0.2)
    assert sim.game["attacks"] == {"cyan": "-x", "magenta": "+x"}
    for page in (console, coach):
        wait_frame(page, sim.time)
        page.wait_for_function("window.simatch.frame.game && window.simatch.frame.game.stage === 'second_half'")
        assert near(goal_colour(page, -1), TEAM_RGB["magenta"]) and near(goal_colour(page, 1), TEAM_RGB["cyan"])
    console.wait_for_function("document.getElementById('ends').textContent === 'cyan ← · magenta →'")
    coach.wait_for_function("document.getElementById('attacks').textContent === '←'")
    keeper = {r["name"]: r for r in coach.evaluate("window.simatch.frame.robots")}["cyan/1"]
    assert keeper["x"] == pytest.approx(10.5, abs=0.1) and abs(keeper["yaw"]) == pytest.approx(math.pi, abs=0.05)
    shot(console, "ends_changed_console")
    shot(coach, "ends_changed_coach")
