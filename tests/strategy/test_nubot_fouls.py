"""Situations from nubot-against-nubot matches where nubot used to foul, rebuilt through the Python API
(no referee: the test gives the game commands and measures what the referee would)."""

from __future__ import annotations

import math

import pytest

from simatch import msgs
from simatch.bus import topics
from simatch.msgs.game_commands import MatchMode as M
from tests.strategy.helpers import bench_all_but, command, run_until, scenario, start

PREPARE = 5.0  # the referee's preparation time before START


#: seed 5, t = 71.5 s: the ball is placed for magenta's throw-in at (5.92, -6.70) (world frame)
THROW_IN = {
    "cyan/2": (5.40, 2.72, -1.25),
    "cyan/3": (5.99, -7.23, -0.26),
    "cyan/4": (-1.16, -1.15, -0.70),
    "cyan/5": (-0.64, -2.64, -0.57),
    "magenta/2": (4.90, -5.15, -0.62),
    "magenta/3": (8.22, -3.92, -2.02),
    "magenta/4": (4.45, 2.21, -2.33),
    "magenta/5": (-0.62, 4.45, -0.92),
}


def place(sim, poses: dict) -> None:
    for name, (x, y, yaw) in poses.items():
        sim.set_model_state(name, x=x, y=y, yaw=yaw, vx=0.0, vy=0.0, wz=0.0)


def test_a_robot_beyond_the_side_line_leaves_the_throw_in_circle_along_the_field():
    """The ball is placed for the opponents' throw-in half a metre from a robot that ran over the side line
    with it, the taker coming to the ball from inside the field. Leaving the 3 m circle straight away from
    the ball drove the robot into the boards, where it stayed (1.6 m from the ball at START: a set-piece
    distance foul); it must go round, along the line."""
    sim = scenario(cyan="nubot", magenta="nubot")
    bx, by = 5.92, -6.70
    place(sim, THROW_IN)
    sim.set_model_state("ball", x=bx, y=by, z=0.11)
    sim.step()
    command(sim, "magenta", M.OUR_THROWIN)
    sim.run(seconds=PREPARE)
    ms = sim.model_states()
    near = {
        n: round(math.hypot(ms[n].x - bx, ms[n].y - by), 2) for n in sim.simulator.robot_names if n.startswith("cyan")
    }
    assert min(near.values()) >= 3.0, near
    sim.close()


#: seed 4 (halves of 150 s), t = 176.85 s: the ball is placed for cyan's throw-in at (-3.11, -6.70)
LATE_TAKER = {
    "cyan/2": (3.78, 1.50, 2.97),
    "cyan/3": (-2.11, -4.99, -2.05),
    "cyan/4": (-7.48, -3.41, -0.96),
    "cyan/5": (-6.97, -2.37, -1.55),
    "magenta/2": (4.60, -3.44, -2.60),
    "magenta/3": (-1.03, -5.55, -2.27),
    "magenta/4": (-7.28, -1.08, -1.01),
    "magenta/5": (2.64, 0.87, -2.57),
}


class Contacts:
    """Every physics step in which a robot touches, holds or kicks the ball: (time, robot names)."""

    def __init__(self, sim):
        self.steps: list[tuple[float, set]] = []
        sim.bus.subscribe(topics.BALL_CONTACTS, msgs.BallContacts, self._on)

    def _on(self, m) -> None:
        names = set(m.touching) | {n for n in (m.holder, m.kicker) if n}
        if names:
            self.steps.append((m.stamp, names))

    def double_touch(self, gap: float = 0.1) -> tuple | None:
        """(robot, time) if the first robot to touch the ball let go of it for ``gap`` s and touched it again
        before any other robot did (the referee's double touch), else None."""
        if not self.steps:
            return None
        first = sorted(self.steps[0][1])[0]
        last = self.steps[0][0]
        for t, names in self.steps:
            if names - {first}:
                return None
            if t - last > gap:
                return first, t
            last = t
        return None


def test_a_taker_that_bumped_the_ball_leaves_it_to_a_team_mate():
    """START comes one second after the ball is placed, the taker still coming from the field side. Going
    round the ball to its line-up point it brushed the ball (0.4 m: not yet in play), then lined up and
    played it again: the referee's double touch. The taker must go round clear of the ball and, if it
    did move the ball, leave it (its team-mates keep 2 m until the ball is in play or the restart times
    out)."""
    sim = scenario(cyan="nubot", magenta="nubot")
    bx, by = -3.11, -6.70
    place(sim, LATE_TAKER)
    sim.set_model_state("ball", x=bx, y=by, z=0.11)
    contacts = Contacts(sim)
    sim.step()
    command(sim, "cyan", M.OUR_THROWIN)
    sim.run(seconds=1.0)
    start(sim)
    t0, closest = sim.time, {}
    while sim.time < t0 + 7.0:
        sim.run(seconds=0.05)
        ms = sim.model_states()
        if math.hypot(ms["ball"].x - bx, ms["ball"].y - by) >= 0.5:
            break  # in play
        if contacts.steps:
            first = sorted(contacts.steps[0][1])[0]
            for n in sim.simulator.robot_names:
                if n.startswith("cyan") and n != first:
                    d = math.hypot(ms[n].x - ms["ball"].x, ms[n].y - ms["ball"].y)
                    closest[n] = min(closest.get(n, 9.0), round(d, 2))
    sim.run(seconds=max(0.0, t0 + 7.0 - sim.time))
    assert contacts.steps and sorted(contacts.steps[0][1])[0].startswith("cyan"), "the throw-in was not taken"
    assert contacts.double_touch() is None, contacts.double_touch()
    # until the ball is in play the taker's team-mates keep 2 m from it
    assert min(closest.values(), default=9.0) >= 2.0, closest
    sim.close()


def test_a_late_kick_off_taker_stays_in_its_half():
    """START comes while the taker still runs in from its own half (seed 5: after a goal, the taker came from
    its goal area). Arriving fast beside the ball it overran the half-way line before the ball was in play
    (the referee's kickoff_half foul). Every robot of the kicking team stays in its half until the ball
    moved 0.5 m."""
    sim = scenario(cyan="nubot", magenta="nubot")
    place(
        sim,
        {
            "cyan/2": (-6.0, 3.0, 0.0),
            "cyan/3": (-8.0, 5.0, 0.0),
            "cyan/4": (-8.0, -5.0, 0.0),
            "cyan/5": (-9.0, 0.0, 0.0),
        },
    )
    sim.set_model_state("ball", x=0.0, y=0.0, z=0.11)
    sim.step()
    command(sim, "cyan", M.OUR_KICKOFF)
    run_until(
        sim,
        lambda: min(math.hypot(p.x, p.y) for n, p in sim.model_states().items() if n.startswith("cyan")) < 1.0,
        10.0,
        step=0.025,
    )
    start(sim)
    worst = (-1.0, "")
    end = sim.time + 7.0
    while sim.time < end:
        sim.run(seconds=0.025)
        ms = sim.model_states()
        if math.hypot(ms["ball"].x, ms["ball"].y) >= 0.5:
            break
        worst = max([worst] + [(ms[n].x, n) for n in sim.simulator.robot_names if n.startswith("cyan")])
    assert worst[0] <= 0.0, f"{worst[1]} at x = {worst[0]:.3f} m before the ball was in play"
    sim.close()


@pytest.mark.parametrize("team, x, y", [("magenta", -11.35, 1.076), ("cyan", 11.35, -1.076), ("cyan", 11.3, 0.2)])
def test_a_robot_caught_in_the_opponents_goal_gets_out(team, x, y):
    """A robot pushed into the opponents' goal beside a post (seed 0's full match: magenta/3 stood there,
    fouled for being in the goal area again and again) leaves it towards the field, not sideways into the
    net."""

    sim = scenario(cyan="nubot" if team == "cyan" else "none", magenta="nubot" if team == "magenta" else "none")
    name = f"{team}/3"
    bench_all_but(sim, [name, f"{team}/1", f"{team}/2"])
    sim.set_model_state(name, x=x, y=y, yaw=0.0, vx=0.0, vy=0.0, wz=0.0)
    sim.set_model_state("ball", x=0.0, y=3.0, z=0.11)
    start(sim)
    sim.run(seconds=4.0)
    r = sim.model_states()[name]
    assert abs(float(r.x)) < 11.0 - 0.75, f"{name} still in the goal area at ({float(r.x):.2f}, {float(r.y):.2f})"
