"""A recorded run driven from the pages (real chromium) is reproduced bit for bit by ``verify``: every web
action goes through calls that the recording keeps (coach commands, Simulation calls, the referee's
operator requests)."""

from __future__ import annotations

import math

from simatch.msgs.game_commands import MatchMode
from simatch.record import Recorder, verify

from .conftest import drag_ball, run_until, wait_frame
from .test_referee_console import REFEREED


def _near(sim, name, x, y, tol=0.15) -> bool:
    s = sim.model_states()[name]
    return math.hypot(s.x - x, s.y - y) < tol


def test_a_coached_run_driven_from_the_pages_is_reproduced(live, open_page, tmp_path):
    sim, view = live(seed=3)  # no referee: a coach per team, robots play 'startpose'
    path = tmp_path / "coached.mcap"
    recorder = Recorder.for_run(sim, path)
    try:
        sim.run(seconds=0.1)
        coach = open_page(view.urls["cyan coach"])
        console = open_page(view.urls["referee"])
        for p in (coach, console):
            wait_frame(p, sim.time)
        cyan = sim.coaches["cyan"]
        coach.click("#start")
        run_until(sim, lambda: cyan.match_mode == MatchMode.STARTROBOT)
        coach.fill("#maxvel", "2.5")
        coach.click("#limits")
        run_until(sim, lambda: cyan.max_vel == 2.5)
        coach.locator("#field").click(position={"x": 300, "y": 200})  # the test's target point
        coach.click("#tsend")
        run_until(sim, lambda: cyan.match_mode == MatchMode.TEST)
        drag_ball(console, sim, -2.0, 3.0)
        run_until(sim, lambda: _near(sim, "ball", -2.0, 3.0))
        console.click("#robots-table tr[data-robot='magenta/4'] button.sendoff")
        run_until(sim, lambda: "magenta/4" in view.control.sent_off)
        sim.run(seconds=0.3)
        console.click("#robots-table tr[data-robot='magenta/4'] button.sendoff")
        run_until(sim, lambda: "magenta/4" not in view.control.sent_off)
        console.click("#pause")
        run_until(sim, lambda: cyan.match_mode == MatchMode.STOPROBOT and sim.coaches["magenta"].match_mode == 0)
        sim.run(seconds=0.5)
    finally:
        recorder.close()
    verdict = verify(path)
    assert verdict.identical and verdict.mode == "inputs" and verdict.inputs > 0, verdict.describe()
    verdict = verify(path, mode="strategies")
    assert verdict.identical, verdict.describe()
    # start, limits, test, the ball, take_control + send_vel + set_model_state, set_model_state + release, 2 x stop
    assert verdict.operator_commands >= 11, verdict.describe()


def test_a_refereed_run_driven_from_the_console_is_reproduced(live, open_page, tmp_path):
    sim, view = live(seed=5, **{**REFEREED, "teams.cyan.strategy": "startpose", "teams.magenta.strategy": "startpose"})
    path = tmp_path / "refereed.mcap"
    recorder = Recorder.for_run(sim, path)
    try:
        sim.run(seconds=0.1)
        page = open_page(view.urls["referee"])
        wait_frame(page, sim.time)
        page.click("#pause")
        run_until(sim, lambda: sim.game["paused"])
        sim.run(seconds=0.3)
        page.click("#resume")
        run_until(sim, lambda: not sim.game["paused"])
        page.click("#teamsel button[data-team='magenta']")
        page.click("#setpieces button[data-cmd='OUR_FREEKICK']")
        run_until(sim, lambda: sim.game["restart"] is not None and "free kick for magenta" in sim.game["restart"])
        drag_ball(page, sim, -3.0, -5.0)
        run_until(sim, lambda: _near(sim, "ball", -3.0, -5.0))
        page.click("#robots-table tr[data-robot='cyan/5'] button.sendoff")
        run_until(sim, lambda: "cyan/5" in sim.game["sent_off"])
        page.click("#robots-table tr[data-robot='magenta/3'] button.red")
        run_until(sim, lambda: "magenta/3" in sim.game["sent_off"])
        page.click("#auto")
        run_until(sim, lambda: sim.game["manual"])
        page.click("#teams tr[data-team='cyan'] button.goal")
        run_until(sim, lambda: sim.game["score"]["cyan"] == 1)
        page.click("#start")
        run_until(sim, lambda: sim.game["phase"] in ("taking", "play"))
        sim.run(seconds=1.0)
    finally:
        recorder.close()
    operator = [e for e in sim.events if e["type"] == "operator"]
    assert len(operator) == 9 and not [e for e in sim.events if e["type"] == "operator_refused"]
    verdict = verify(path)
    assert verdict.identical and verdict.mode == "inputs", verdict.describe()
    verdict = verify(path, mode="strategies")
    assert verdict.identical, verdict.describe()
    assert verdict.operator_commands == 9, verdict.describe()
