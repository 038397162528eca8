"""The README's Python API example does what it says, run as it is written; and the API says when a judge undoes
a state the caller set (the example used to set the ball at the very step the referee placed it for the kick-off,
which undid it without a word)."""

from __future__ import annotations

import math
import re
import warnings
from pathlib import Path

import pytest

import simatch

README = Path(__file__).resolve().parents[1] / "README.md"


def _api_example() -> str:
    text = README.read_text(encoding="utf-8")
    section = text.split("### Python API", 1)[1]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


@pytest.mark.slow
def test_the_readme_python_api_example_does_what_it_says():
    code = _api_example()
    scope: dict = {}
    with warnings.catch_warnings():
        warnings.simplefilter("error", simatch.StateOverridden)  # nothing the example sets is undone
        exec(compile(code, str(README), "exec"), scope)
    sim, match = scope["sim"], scope["match"]
    try:
        # the ball was set at (1.0, 0.5) rolling at 3 m/s and pushed on: a second later it is well on its way
        ball = sim.model_states()["ball"]
        assert ball.x > 3.0 and abs(ball.y - 0.5) < 0.3, (ball.x, ball.y)
        # the robot taken over drove forward and turned
        assert sim.time == pytest.approx(3.0)
        assert math.hypot(*sim.link_states()["cyan/2/wheel_1"][0][:2]) > 0
        # the referee's operator placed the ball where the example says, in a refereed match
        match.run(seconds=0.05)
        ball = match.model_states()["ball"]
        assert math.hypot(ball.x - 1.0, ball.y - 0.5) < 0.2, (ball.x, ball.y)
        placed = [
            e for e in match.events if e["type"] == "ball_placed" and e.get("detail") == "the operator placed the ball"
        ]
        assert placed and (placed[-1]["x"], placed[-1]["y"]) == (1.0, 0.5)
        assert match.game["stage"] == "first_half" and set(match.result()["result"]["score"]) == {"cyan", "magenta"}
    finally:
        sim.close()
        match.close()


def test_a_state_the_referee_undoes_is_reported():
    """The old example: the ball set at t = 2.0 s, the step at which the referee places it for the kick-off."""
    with simatch.Simulation("msl_5v5", seed=1, overrides={"teams.magenta.strategy": "startpose"}) as sim:
        sim.run(seconds=2.0)
        sim.set_model_state("ball", x=1.0, y=0.5, z=0.11, vx=3.0)
        with pytest.warns(simatch.StateOverridden, match=r"moved 'ball' at t = 2\.000 s.*kick-off.*place_ball") as got:
            sim.run(seconds=0.1)
        assert len(got) == 1 and got[0].filename == __file__, "the warning points at the caller's run()"
        ball = sim.model_states()["ball"]
        assert (ball.x, ball.y) == (0.0, 0.0)
        # said once per set state: running on says nothing more
        with warnings.catch_warnings():
            warnings.simplefilter("error", simatch.StateOverridden)
            sim.run(seconds=1.5)


def test_a_state_set_where_nothing_undoes_it_is_not_reported():
    with warnings.catch_warnings():
        warnings.simplefilter("error", simatch.StateOverridden)
        # no referee
        with simatch.Simulation("msl_5v5", overrides={"judge.kind": "none"}) as sim:
            sim.run(seconds=2.0)
            sim.set_model_state("ball", x=1.0, y=0.5, vx=3.0)
            sim.run(seconds=0.5)
            assert sim.model_states()["ball"].x > 2.0
        # a referee, but play is on and stays on
        with simatch.Simulation("msl_5v5", seed=1, overrides={"teams.magenta.strategy": "simple"}) as sim:
            sim.run(seconds=20.0)
            assert sim.game["phase"] == "play"
            sim.set_model_state("ball", x=0.0, y=1.0, vx=0.3)
            at = sim.time
            sim.step(40)
            assert not [e for e in sim.events if e["t"] >= at and e["type"] == "ball_placed"]


def test_the_readme_gives_the_locomotion_test_figures_it_measures():
    """The figures of `simatch run omni_circle` beside the paper's, as the README prints them."""
    text = README.read_text(encoding="utf-8").split("### The paper's locomotion test", 1)[1].split("\n## ", 1)[0]
    rows = {
        line.split("|")[1].strip(): [c.strip() for c in line.split("|")[2:5]]
        for line in text.splitlines()
        if line.startswith("| ")
    }
    with simatch.Simulation("omni_circle") as sim:
        sim.run()
        r = sim.result()["result"]
    assert rows["samples"] == [str(r["paper"]["samples"]), str(r["samples"]), str(r["samples"])]
    position = rows["mean position error (distance to the centre - radius)"]
    assert position[0] == f"{r['paper']['position_error_cm']} cm"
    assert (
        position[1] == f"{r['position_error_cm']:.4f} cm" and position[2] == f"{r['position_error_expected_cm']:.4f} cm"
    )
    heading = rows["mean orientation error (heading - w t)"]
    assert heading[0] == f"{r['paper']['orientation_error_rad']} rad"
    assert heading[1] == f"{r['orientation_error_rad']:.4f} rad"
    assert heading[2].startswith(f"{r['orientation_error_expected_rad']:.4f} rad")
    assert r["orientation_error_vs_ideal_rad"] < 1e-9
