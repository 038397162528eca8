"""Recordings in the pages: ``simatch replay FILE.mcap --view`` and ``simatch serve FILE.mcap`` on a real
recording made by ``simatch run ... --record``, watched in real chromium."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from simatch.record import Recording

from .conftest import shot
from .test_cli import _finish, _start, _urls

#: magenta's robots drive in circles so that the recording moves
CIRCLES = [
    "--set",
    "teams.magenta.strategy=constant",
    "--set",
    "teams.magenta.strategy_params.vx=1.0",
    "--set",
    "teams.magenta.strategy_params.w=1.0",
]


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    path = tmp_path_factory.mktemp("recording") / "match.mcap"
    subprocess.run(
        [
            sys.executable,
            "-m",
            "simatch",
            "run",
            "msl_5v5",
            "--duration",
            "3",
            "--quiet",
            "--record",
            str(path),
            *CIRCLES,
        ],
        check=True,
        timeout=120,
        stdout=subprocess.DEVNULL,
    )
    return path


def _recorded_at(path, t: float) -> dict[str, tuple[float, float]]:
    """Every model's (x, y) in the recorded model states stamped ``t``."""
    for _, _, msg in Recording(path).messages(topics={"model_states"}):
        if abs(msg.stamp - t) < 5e-4:
            pose = np.asarray(msg.pose).reshape(-1, 7)
            return {name: (pose[k, 0], pose[k, 1]) for k, name in enumerate(msg.name)}
    raise AssertionError(f"no model states recorded at t={t}")


@pytest.mark.parametrize("command", [["replay", "{file}", "--view"], ["serve", "{file}"]])
def test_a_recording_plays_in_the_live_pages_and_the_replay_page_goes_through_it(recording, command, open_page):
    proc = _start(*[a.format(file=recording) for a in command], "--view-port", "0")
    try:
        urls = _urls(proc)
        assert set(urls) == {"cyan coach", "magenta coach", "referee", "replay", "3d view"}
        # the replay page: the whole recording, loaded from the file, with a timeline of its own
        replay = open_page(urls["replay"])
        replay.wait_for_function("window.simatch.frame && window.simatch.frame.timeline.complete")
        timeline = replay.evaluate("window.simatch.frame.timeline")
        assert timeline["start"] == pytest.approx(0.0, abs=0.02) and timeline["end"] == pytest.approx(3.0, abs=0.02)
        replay.click("#play")
        replay.wait_for_function("!window.simatch.frame.timeline.playing")
        replay.select_option("#speed", "4")
        replay.wait_for_function("window.simatch.frame.timeline.speed === 4")
        replay.evaluate("window.simatch.conn.request({type: 'timeline', action: 'seek', value: 2.5})")
        replay.wait_for_function("Math.abs(window.simatch.frame.timeline.t - 2.5) < 0.02")
        frame = replay.evaluate("window.simatch.frame")
        truth = _recorded_at(recording, frame["t"])
        for robot in frame["robots"]:
            assert (robot["x"], robot["y"]) == pytest.approx(truth[robot["name"]], abs=1e-3), robot["name"]
        assert (frame["ball"]["x"], frame["ball"]["y"]) == pytest.approx(truth["ball"], abs=1e-3)
        assert "kick-off for cyan" in replay.inner_text("#events"), "the events up to the moment shown"
        shot(replay, f"recording_replay_{command[0]}")
        replay.click("#play")
        replay.wait_for_function("window.simatch.frame.timeline.t > 2.7")

        # the referee console watches the replayed bus: the recorded game state, nothing to command
        console = open_page(urls["referee"])
        console.wait_for_function(
            "window.simatch.frame && window.simatch.frame.game && window.simatch.frame.t > 2.5", timeout=20_000
        )
        assert console.inner_text("#stage") == "first_half"
        assert console.locator("#pause").is_disabled() and "recording" in console.inner_text("#mode-note")
        answer = console.evaluate("""async () => {
            try { await window.simatch.conn.request({type: 'pause'}); return 'accepted'; }
            catch (e) { return e.message; } }""")
        assert "is a recording" in answer
        magenta = {r["name"]: r for r in console.evaluate("window.simatch.frame.robots")}["magenta/3"]
        assert (magenta["x"], magenta["y"]) != pytest.approx((3.5, 1.0), abs=0.1), "magenta drives in circles"
        shot(console, f"recording_console_{command[0]}")
        for page in (replay, console):
            page.close()
        out, err = _finish(proc, timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 0, err
    assert "replayed" in out
