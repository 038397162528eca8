"""Set pieces: for every game command both nubot teams take positions that keep the MSL distances, from
robots scattered over the field, within the time a referee gives them; and then the restart is played."""

from __future__ import annotations

import math

import numpy as np
import pytest

from simatch.msgs.game_commands import MatchMode as M
from tests.strategy.helpers import BallWatch, command, run_until, scenario, start

PREPARE = 5.0  # the referee's preparation time (kick-off: 10 s)
L2, W2, PA_DEPTH, PA_HALF = 11.0, 7.0, 2.25, 3.45


def scatter(sim, seed: int) -> None:
    rng = np.random.default_rng(seed)
    for name in sim.simulator.robot_names:
        if name.endswith("/1"):
            continue  # goalkeepers are at their goals
        sim.set_model_state(
            name, x=float(rng.uniform(-9, 9)), y=float(rng.uniform(-6, 6)), yaw=float(rng.uniform(-3, 3))
        )


def in_penalty_area(x: float, y: float, side: int) -> bool:
    return side * x >= L2 - PA_DEPTH and abs(y) <= PA_HALF


CASES = [
    (M.OUR_KICKOFF, "cyan", (0.0, 0.0)),
    (M.OUR_KICKOFF, "magenta", (0.0, 0.0)),
    (M.OUR_FREEKICK, "cyan", (3.0, 2.0)),
    (M.OUR_FREEKICK, "magenta", (-4.0, -3.0)),
    (M.OUR_THROWIN, "cyan", (2.0, 6.7)),
    (M.OUR_THROWIN, "magenta", (-5.0, -6.7)),
    (M.OUR_GOALKICK, "cyan", (-7.4, 3.5)),
    (M.OUR_GOALKICK, "magenta", (7.4, -3.5)),
    (M.OUR_CORNERKICK, "cyan", (10.7, 6.7)),
    (M.OUR_CORNERKICK, "magenta", (-10.7, -6.7)),
    (M.OUR_PENALTY, "cyan", (8.0, 0.0)),
    (M.OUR_PENALTY, "magenta", (-8.0, 0.0)),
    (M.DROPBALL, "cyan", (1.0, 1.0)),
]


@pytest.mark.parametrize("cmd,team,spot", CASES, ids=[f"{M(c).name}-{t}" for c, t, _ in CASES])
def test_set_piece_positions_keep_their_distances(cmd, team, spot):
    sim = scenario(cyan="nubot", magenta="nubot")
    scatter(sim, seed=cmd * 7 + (team == "magenta"))
    bx, by = spot
    sim.set_model_state("ball", x=bx, y=by, z=0.11)
    sim.step()
    command(sim, team, cmd)
    sim.run(seconds=10.0 if cmd == M.OUR_KICKOFF else PREPARE)
    ms = sim.model_states()
    other = "magenta" if team == "cyan" else "cyan"
    sign = {"cyan": 1, "magenta": -1}
    d = {n: math.hypot(ms[n].x - bx, ms[n].y - by) for n in sim.simulator.robot_names}
    kicker = min((n for n in d if n.startswith(team)), key=d.get)
    problems = []
    for n, dist in d.items():
        t, keeper = n.split("/")[0], n.endswith("/1")
        x, y = ms[n].x, ms[n].y
        own_area = in_penalty_area(x, y, -sign[t])
        if cmd == M.DROPBALL:
            if dist < 1.0 and not own_area:
                problems.append(f"{n} {dist:.2f} m from a dropped ball")
            continue
        if cmd == M.OUR_PENALTY:
            if n == kicker or (t == other and keeper):
                continue
            if dist < 3.0 or in_penalty_area(x, y, sign[team]):
                problems.append(f"{n} at ({x:.2f}, {y:.2f}) during the penalty")
            continue
        if t == other and dist < 3.0 and not own_area:
            problems.append(f"opponent {n} {dist:.2f} m from the ball")
        if t == team and n != kicker and dist < 2.0:
            problems.append(f"team-mate {n} {dist:.2f} m from the ball")
        if cmd == M.OUR_KICKOFF and sign[t] * x > 0.0:
            problems.append(f"{n} in the opponent half at x={x:.2f}")
    for n in sim.simulator.robot_names:
        t = n.split("/")[0]
        if not n.endswith("/1") and in_penalty_area(ms[n].x, ms[n].y, -sign[t]):
            problems.append(f"{n} stands in its own penalty area")
    assert not problems, problems
    sim.close()


@pytest.mark.parametrize(
    "cmd,team,spot",
    [
        (M.OUR_KICKOFF, "cyan", (0.0, 0.0)),
        (M.OUR_FREEKICK, "magenta", (-3.0, 2.0)),
        (M.OUR_THROWIN, "cyan", (-2.0, -6.7)),
        (M.OUR_CORNERKICK, "cyan", (10.7, -6.7)),
    ],
)
def test_the_restart_is_a_pass_taken_at_once(cmd, team, spot):
    """After START the taker kicks within the 7 s the rules give, without dribbling (it never holds the
    ball), as a pass: the ball heads for a team-mate (at a kick-off, to stop in front of one); and
    the taker does not touch the ball again before another robot did."""
    sim = scenario(cyan="nubot", magenta="nubot")
    bx, by = spot
    sim.set_model_state("ball", x=bx, y=by, z=0.11)
    watch = BallWatch(sim)
    sim.step()
    command(sim, team, cmd)
    sim.run(seconds=10.0 if cmd == M.OUR_KICKOFF else PREPARE)
    t0 = sim.time
    start(sim)
    assert run_until(sim, lambda: bool(watch.kicks), 7.0, step=0.01), "the restart was not taken within 7 s"
    t_kick, taker, _ = watch.kicks[0]
    assert taker.startswith(team) and t_kick - t0 < 7.0
    assert not any(h == taker for t, h in watch.holders if t <= t_kick), "the taker dribbled"
    ms = sim.model_states()
    b = ms["ball"]
    heading = math.atan2(b.vy, b.vx)
    lead = 0.6 if cmd == M.OUR_KICKOFF else 0.0  # a kick-off pass stops in front of the receiver
    aimed = []
    for n in sim.simulator.robot_names:
        if n.startswith(team) and n != taker:
            rx, ry = ms[n].x - b.x, ms[n].y - b.y
            along = rx * math.cos(heading) + ry * math.sin(heading)
            across = abs(-rx * math.sin(heading) + ry * math.cos(heading))
            if along > 0.5 and across < 0.6 + lead:
                aimed.append(n)
    assert aimed, "the restart kick was not played to a team-mate"
    run_until(sim, lambda: any(n != taker for _, n in watch.touches if _ > t_kick + 0.05), 6.0)
    first_other = next(t for t, n in watch.touches if t > t_kick + 0.05 and n != taker)
    assert not [t for t, n in watch.touches if n == taker and t_kick + 0.2 < t < first_other], (
        "the taker touched the ball again before another robot did"
    )
    sim.close()
