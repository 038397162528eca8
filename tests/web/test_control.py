"""What the pages' requests call in each kind of run, without a browser (fast): the requests are carried out
by the run's control node inside real runs, and answered as the pages would be."""

from __future__ import annotations

import simatch
from simatch.msgs.game_commands import MatchMode
from simatch.web import protocol as P
from simatch.web.access import Grant
from simatch.web.control import RunControl

REFEREE, CYAN = Grant("referee"), Grant("coach", "cyan")


def ask(sim, control, grant, text: str, steps: int = 3):
    """Submit a page's message, step the run until it is answered; the answer (None: done, else the error)."""
    answers = []
    control.submit(grant, P.parse(text, grant.role), answers.append)
    for _ in range(steps):
        if answers:
            break
        sim.step()
    assert answers, "no answer"
    return answers[0]


def test_a_judge_that_gives_the_commands_but_takes_no_requests_is_left_alone():
    with simatch.Simulation("encirclement_9v7") as sim:
        control = RunControl(sim)
        sim.step()
        assert not control.has_referee and control.capabilities(REFEREE)["commands"] is False
        assert "the judge (encirclement) gives the commands" in ask(sim, control, REFEREE, '{"type": "pause"}')
        assert "gives the commands" in ask(sim, control, CYAN, '{"type": "command", "cmd": "STARTROBOT"}')
        assert "needs one" in ask(sim, control, REFEREE, '{"type": "auto_referee", "on": false}')
        assert "no room beside it" in ask(sim, control, REFEREE, '{"type": "send_off", "robot": "magenta/2"}')
        assert ask(sim, control, REFEREE, '{"type": "place_ball", "x": -3.0, "y": 2.0}') is None
        ball = sim.model_states()["ball"]
        assert (ball.x, ball.y) == (-3.0, 2.0)
        control.close()


def test_new_limits_keep_the_test_a_coach_is_running():
    with simatch.Simulation("msl_5v5", overrides={"judge.kind": "none"}) as sim:
        control = RunControl(sim)
        coach = sim.coaches["cyan"]
        assert ask(sim, control, CYAN, '{"type": "test", "mode": "move", "robot": 3, "x": 2.0, "y": -1.0}') is None
        test = dict(coach.extra)
        assert ask(sim, control, CYAN, '{"type": "limits", "max_vel": 2.0, "max_w": 4.0}') is None
        assert (coach.max_vel, coach.max_w) == (2.0, 4.0)
        assert coach.match_mode == MatchMode.TEST and coach.extra == test
        assert sim.events[-1]["type"] == "coach_command", "limits are a coach command, so a recording keeps them"
        assert "commands cyan only" in ask(sim, control, CYAN, '{"type": "command", "cmd": 0, "team": "magenta"}')
        control.close()


def test_the_referees_answer_reaches_the_page_that_asked():
    with simatch.Simulation("msl_5v5") as sim:
        control = RunControl(sim)
        sim.step()
        assert ask(sim, control, REFEREE, '{"type": "card", "robot": "cyan/4", "card": "yellow"}') is None
        assert sim.game["yellow_cards"]["cyan"] == 1
        assert ask(sim, control, REFEREE, '{"type": "place_ball", "x": 40.0, "y": 0.0}').startswith(
            "the referee refused: (40.00, 0.00) is not on the floor"
        )
        assert "no robot named" in ask(sim, control, REFEREE, '{"type": "card", "robot": "cyan/9", "card": "red"}')
        assert "limits are its settings" in ask(sim, control, REFEREE, '{"type": "limits", "max_vel": 2, "max_w": 3}')
        waiting = []
        control.submit(REFEREE, P.parse('{"type": "pause"}', "referee"), waiting.append)
        control.close()  # the run ends before the referee could answer
        assert waiting == ["the run has ended"]


def test_the_referees_operator_requests_are_recorded_and_made_again(tmp_path):
    """Requests from the console (on the bus, within steps) and from a script (the Python API, between steps)
    are recorded by the referee and made again by verification at the same point."""
    from simatch.record import Recorder, Recording, verify

    path = tmp_path / "operated.mcap"
    with simatch.Simulation("msl_5v5", seed=2) as sim, Recorder.for_run(sim, path):
        control = RunControl(sim)
        sim.run(seconds=0.5)
        assert ask(sim, control, REFEREE, '{"type": "place_ball", "x": 3.0, "y": 1.0}') is None
        assert ask(sim, control, REFEREE, '{"type": "send_off", "robot": "cyan/2"}') is None
        sim.run(seconds=0.5)
        sim.judge.pause()
        sim.run(seconds=0.3)
        sim.judge.resume()
        sim.judge.place_ball(-2.0, 2.5)
        sim.run(seconds=0.5)
        assert ask(sim, control, REFEREE, '{"type": "send_off", "robot": "cyan/2", "off": false}') is None
        sim.run(seconds=1.0)
        control.close()
    calls = [(m.call, m.during_step) for _, _, m in Recording(path).messages(topics={"operator"})]
    assert calls == [("judge.request", False)] * 2 + [
        ("judge.pause", False),
        ("judge.resume", False),
        ("judge.place_ball", False),
        ("judge.request", False),
    ]
    assert verify(path).identical, verify(path).describe()  # the world from its recorded inputs
    verdict = verify(path, mode="strategies")
    assert verdict.identical and verdict.operator_commands == 6, verdict.describe()
