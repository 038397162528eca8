"""The web UI in real headless chromium against a real run: what the issue asks the browser to prove."""

from __future__ import annotations

import math

import pytest

from simatch.msgs.game_commands import MatchMode

from .conftest import drag_ball, run_until, shot, wait_frame

TEAM_RGB = {"cyan": (0x19, 0xC6, 0xDA), "magenta": (0xE0, 0x35, 0x9C)}

PIXEL_AT = """([x, y, yaw, along]) => {
  const v = window.simatch.view, dpr = window.devicePixelRatio || 1;
  const r = 0.25 * v.scale * along;
  const [px, py] = v.toScreen(x, y);
  // beside the centre, across the heading line (the id label is outside the disc)
  const sx = Math.round((px + r * Math.sin(yaw)) * dpr), sy = Math.round((py + r * Math.cos(yaw)) * dpr);
  const d = v.ctx.getImageData(sx, sy, 1, 1).data;
  return [d[0], d[1], d[2]];
}"""


def near(rgb, want, tol=40) -> bool:
    return all(abs(a - b) <= tol for a, b in zip(rgb, want))


def test_pages_load_with_the_field_to_scale(live, open_page):
    sim, view = live()
    sim.run(seconds=0.2)
    for label, name in (
        ("cyan coach", "coach_cyan"),
        ("magenta coach", "coach_magenta"),
        ("referee", "referee"),
        ("replay", "replay"),
    ):
        page = open_page(view.urls[label])
        wait_frame(page, sim.time)
        hello = page.evaluate("window.simatch.hello")
        assert hello["scene"] == "msl_5v5" and hello["field"]["length"] == 22.0
        if label.endswith("coach"):
            assert hello["role"] == "coach" and hello["team"] == label.split()[0]
        # to scale: the goal lines are 22 m apart and the side lines 14 m, at one and the same scale
        (x0, y0), (x1, y1) = page.evaluate(
            "[window.simatch.view.toScreen(-11, 7), window.simatch.view.toScreen(11, -7)]"
        )
        assert (x1 - x0) / (y1 - y0) == pytest.approx(22.0 / 14.0, rel=1e-6)
        width = page.evaluate("window.simatch.view.w")
        assert x1 - x0 <= width and x1 - x0 >= 0.5 * width
        # the halfway line is drawn white where the field says
        rgb = page.evaluate(PIXEL_AT, [0.0, 3.0, 0.0, 0.0])
        assert min(rgb) > 200, f"halfway line not white at (0, 3): {rgb}"
        shot(page, f"load_{name}")


def test_robots_are_drawn_where_the_simulator_says(live, open_page):
    sim, view = live(**{"teams.cyan.strategy": "none", "teams.magenta.strategy": "none"})
    spots = {
        "cyan/2": (-6.0, 4.0, 0.3),
        "cyan/4": (3.0, -5.0, 2.0),
        "magenta/3": (7.5, 2.5, -1.0),
        "magenta/5": (-1.0, -2.5, 3.0),
    }
    for name, (x, y, yaw) in spots.items():
        sim.set_model_state(name, x=x, y=y, yaw=yaw)
    sim.run(seconds=0.2)
    truth = sim.model_states()
    referee = open_page(view.urls["referee"])
    coach = open_page(view.urls["cyan coach"])
    for page in (referee, coach):
        wait_frame(page, sim.time)
    for name in truth:
        if name == "ball":
            continue
        s = truth[name]
        team = name.split("/")[0]
        rgb = referee.evaluate(PIXEL_AT, [s.x, s.y, s.yaw, 0.5])
        assert near(rgb, TEAM_RGB[team]), f"{name} at ({s.x:.2f}, {s.y:.2f}): the console shows {rgb} there"
        if team == "cyan":  # a coach draws its own robots from their perception (exact here)
            rgb = coach.evaluate(PIXEL_AT, [s.x, s.y, s.yaw, 0.5])
            assert near(rgb, TEAM_RGB[team]), f"{name}: the cyan coach shows {rgb} there"
    frame = referee.evaluate("window.simatch.frame")
    drawn = {r["name"]: r for r in frame["robots"]}
    for name in spots:
        assert drawn[name]["x"] == pytest.approx(truth[name].x, abs=1e-3)
        assert drawn[name]["y"] == pytest.approx(truth[name].y, abs=1e-3)
        assert math.remainder(drawn[name]["yaw"] - truth[name].yaw, 2 * math.pi) == pytest.approx(0.0, abs=1e-3)
    status = coach.locator("#robots tbody tr[data-robot='2'] td").all_inner_texts()
    assert status[3:5] == ["-6.00", "4.00"]
    shot(referee, "drawn_referee")
    shot(coach, "drawn_coach_cyan")


def _speeds(sim, team):
    return [math.hypot(s.vx, s.vy) for n, s in sim.model_states().items() if n.startswith(team + "/")]


def _displace(sim, team):
    """Push a team's robots 3 m off their start poses, away from the halfway line's axis (no two paths
    cross): a playing 'startpose' robot drives back, a stopped one stands."""
    for name, s in sim.model_states().items():
        if name.startswith(team + "/"):
            sim.set_model_state(name, x=s.x, y=s.y + (-3.0 if s.y <= 0 else 3.0))


def test_stop_button_and_space_key_stop_the_team_in_the_simulation(live, open_page):
    sim, view = live()  # both teams play the plumbing strategy: back to the start pose, still on STOP
    cyan, magenta = sim.coaches["cyan"], sim.coaches["magenta"]
    sim.run(seconds=0.1)
    page = open_page(view.urls["cyan coach"])
    wait_frame(page, sim.time)
    magenta.start_play()
    for stop in ("button", "space"):
        page.click("#start")
        run_until(sim, lambda: cyan.match_mode == MatchMode.STARTROBOT)
        _displace(sim, "cyan")
        sim.run(seconds=0.4)
        assert min(_speeds(sim, "cyan")) > 0.5, "cyan robots should be driving back to their start poses"
        if stop == "button":
            page.click("#stop")
        else:
            page.locator("#field").click(position={"x": 5, "y": 5})  # focus on the page, not in a field
            page.keyboard.press("Space")
        run_until(sim, lambda: cyan.match_mode == MatchMode.STOPROBOT)
        _displace(sim, "magenta")
        sim.run(seconds=0.6)
        assert max(_speeds(sim, "cyan")) < 0.05, f"after {stop}: cyan still moving {_speeds(sim, 'cyan')}"
        assert min(_speeds(sim, "magenta")) > 0.5, "magenta is not this coach's team and keeps playing"
        wait_frame(page, sim.time)
        assert page.inner_text("#mode") == "STOPROBOT"
        shot(page, f"stopped_by_{stop}")
    assert (
        sum(e["type"] == "coach_command" and e["team"] == "cyan" and e.get("detail") == "STOPROBOT" for e in sim.events)
        == 2
    )


def test_a_coach_token_cannot_command_the_other_team(live, open_page):
    sim, view = live()
    sim.run(seconds=0.1)
    cyan_token = view.access.token("coach", "cyan")
    page = open_page(view.urls["cyan coach"])
    wait_frame(page, sim.time)
    before = sim.coaches["magenta"].match_mode
    answer = page.evaluate("""async () => {
        try {
            await window.simatch.conn.request({type: 'command', cmd: 'STARTROBOT', team: 'magenta'});
            return 'accepted';
        }
        catch (e) { return e.message; } }""")
    assert "commands cyan only" in answer
    # the cyan token on magenta's page is still cyan's coach: its buttons command cyan
    other = open_page(view.server.base_url + f"/coach/magenta?token={cyan_token}")
    wait_frame(other, sim.time)
    assert other.evaluate("window.simatch.hello.team") == "cyan"
    other.click("#start")
    run_until(sim, lambda: sim.coaches["cyan"].match_mode == MatchMode.STARTROBOT)
    sim.run(seconds=0.1)
    assert sim.coaches["magenta"].match_mode == before
    # a made-up token gets nothing at all
    bad = open_page(view.server.base_url + "/coach/magenta?token=not-a-token")
    bad.wait_for_function("document.getElementById('conn').textContent === 'refused'")
    assert bad.evaluate("window.simatch.hello") is None
    assert sim.coaches["magenta"].match_mode == before
    shot(bad, "refused_token")


def test_without_a_referee_the_console_places_the_ball_and_sends_a_robot_off(live, open_page):
    sim, view = live()
    sim.run(seconds=0.1)
    page = open_page(view.urls["referee"])
    wait_frame(page, sim.time)
    assert page.locator("#auto").is_disabled() and page.locator("#resume").is_disabled()
    assert "no automatic referee" in page.inner_text("#mode-note")
    drag_ball(page, sim, 4.0, -3.0)
    run_until(sim, lambda: math.hypot(sim.model_states()["ball"].x - 4.0, sim.model_states()["ball"].y + 3.0) < 0.1)
    off = "#robots-table tr[data-robot='cyan/3'] button.sendoff"
    page.click(off)
    run_until(sim, lambda: "cyan/3" in view.control.sent_off)
    sim.run(seconds=0.3)
    s = sim.model_states()["cyan/3"]
    assert abs(s.y) > 7.0, "a robot sent off stands beside the field"
    wait_frame(page, sim.time)
    page.wait_for_selector("#robots-table tr.off[data-robot='cyan/3']")
    page.locator("#events li.send_off").wait_for()
    shot(page, "ball_placed_robot_sent_off")
    page.click(off)
    run_until(sim, lambda: "cyan/3" not in view.control.sent_off)
    assert abs(sim.model_states()["cyan/3"].y) < 7.0


def test_replay_plays_pauses_changes_speed_and_seeks(live, open_page):
    sim, view = live(**{"teams.cyan.strategy": "none", "teams.magenta.strategy": "none"})
    sim.take_control("cyan/2")
    sim.send_vel("cyan/2", 1.0, 0.0, 0.0)
    at_one = None
    while sim.time < 3.0:
        sim.run(seconds=0.05)
        if at_one is None and sim.time >= 1.0:
            at_one = (sim.time, sim.model_states()["cyan/2"].x)
    page = open_page(view.urls["replay"])
    page.wait_for_function("window.simatch.frame && window.simatch.frame.timeline")
    page.click("#play")  # it starts playing: pause it
    page.wait_for_function("!window.simatch.frame.timeline.playing")
    page.select_option("#speed", "4")
    page.wait_for_function("window.simatch.frame.timeline.speed === 4")
    page.evaluate(f"window.simatch.conn.request({{type: 'timeline', action: 'seek', value: {at_one[0]!r}}})")
    page.wait_for_function("t => Math.abs(window.simatch.frame.timeline.t - t) < 1e-3", arg=at_one[0])
    drawn = {r["name"]: r for r in page.evaluate("window.simatch.frame.robots")}
    assert drawn["cyan/2"]["x"] == pytest.approx(at_one[1], abs=0.03)
    assert page.inner_text("#play") == "Play"
    shot(page, "replay_paused_at_1s")
    page.click("#play")
    page.wait_for_function("window.simatch.frame.timeline.t > %r" % (at_one[0] + 0.5))
    page.click("#live")
    page.wait_for_function("t => window.simatch.frame.timeline.t >= t", arg=round(sim.time - 0.02, 3))


def test_pages_reconnect_by_themselves_and_many_watch_at_once(live, open_page):
    sim, view = live()
    pages = [open_page(view.urls[label]) for label in ("cyan coach", "magenta coach", "referee", "referee")]
    sim.run(seconds=0.3)
    assert sim.pace == 1.0, "a live page paces the run at real time"
    for p in pages:
        wait_frame(p, sim.time)
    view.server.stop()
    pages[2].wait_for_function("document.getElementById('conn').textContent === 'reconnecting…'")
    view.server.start()  # same port: the pages come back without a reload
    sim.run(seconds=0.3)
    for p in pages:
        p.wait_for_function("document.getElementById('conn').textContent === 'live'", timeout=15_000)
        wait_frame(p, sim.time, timeout=15_000)
    counts = [p.evaluate("window.simatch.conn.framesReceived") for p in pages]
    assert min(counts) >= 5, counts
    for p in pages:
        p.close()
    run_until(sim, lambda: view.server.live_viewers == 0, timeout=10)
    assert sim.pace is None, "with no page open the run goes back to its own pace"
