"""Who touched the ball, step by step, from the simulator's ``ball_contacts`` (its ball bumper).

Kept at the physics rate, because a deflection lasts a step or two:

* the last robot to touch the ball (ball out: who gets the restart), and where it stood then (a goal's
  shooter must stand in the opponent half);
* every robot that touched the ball since the last restart, in order (no direct goal from a set piece);
* the taker of a set piece, and whether it touched the ball again after letting it go, before any other
  robot did (double touch);
* possession for the dribbling rule: the robot in sole contact with the ball and the point where it took
  the ball; another robot alone on the ball takes possession over, a duel of two keeps it with the robot
  that had it, and the possession ends when the ball is ``dribble_release_distance`` away from the robot;
* the team on the ball (RC-10.1.2): a team *wins* (regains) the ball when one of its robots touches it and
  the previous touch since the restart was the other team's or nobody's; where the ball was then decides
  whether it was won in the team's own half (the ball's centre behind the half-way line). From then on the
  team has *passed* once a team-mate (another robot than the one that touched the ball before) touched it
  with the ball's centre in the opponent half after it rolled freely — untouched — at least
  ``regain_pass_roll``;
* the last kick (robot, step, where the robot stood), for the lob rule.
"""

from __future__ import annotations

import math

from .observation import Observation


class Touches:
    def __init__(self, obs: Observation, release_distance: float, double_touch_gap_steps: int, pass_roll: float = 1.0):
        self.obs = obs
        n = obs.n
        self.release = release_distance
        self.pass_roll = pass_roll
        self.gap_steps = max(1, double_touch_gap_steps)
        self.last = -1  # robot index of the last touch
        self.last_step = -1
        self.touch_x = [0.0] * n  # each robot's position at its last touch
        self.touch_y = [0.0] * n
        self.touch_step = [-1] * n  # and the step of it
        self.since_restart: list[int] = []  # robots that touched since the restart, by first touch
        self._seen = [False] * n
        self.contact: tuple[int, ...] = ()  # robots in contact at `contact_step`
        self.contact_step = -1
        self.holder = -1
        # the set piece's taker (double touch)
        self.armed = False
        self.taker = -1
        self.taker_last_contact = -1
        self.retouch: tuple[int, float, float, int] | None = None  # (step, x, y, steps let go) of a 2nd touch
        self.others_touched = False
        # possession (dribbling)
        self.possessor = -1
        self.start_xy = (0.0, 0.0)
        self.prev_xy = (0.0, 0.0)
        self.backward = 0.0
        # the team on the ball (RC-10.1.2), per team index
        teams = len(obs.teams)
        self.team_on_ball = -1  # team of the last touch since the restart, -1: nobody's
        self.won_by = [-1] * teams  # the robot whose touch won the ball for the team
        self.won_at = [(0.0, 0.0)] * teams  # where the ball was then
        self.won_own_half = [False] * teams
        self.passed = [False] * teams  # a team-mate received it in the opponent half since
        self.longest_roll = [0.0] * teams  # the longest free roll before a team-mate's touch since
        self.ball_at_contact = (0.0, 0.0)  # the ball's position at the last step anybody touched it
        # the last kick: (robot, step, the robot's x, y), None before any
        self.kick: tuple[int, int, float, float] | None = None

    # --- restarts ----------------------------------------------------------------------------------------
    def on_restart(self) -> None:
        """The ball was placed for a restart: history since the restart begins again."""
        self.since_restart.clear()
        self._seen = [False] * self.obs.n
        self.armed = False
        self.taker = -1
        self.retouch = None
        self.others_touched = False
        self.possessor = -1
        self.team_on_ball = -1

    def arm_taker(self) -> None:
        """START of a set piece: the first robot to touch the ball now is its taker."""
        self.armed = True
        self.taker = -1
        self.retouch = None
        self.others_touched = False

    def disarm(self) -> None:
        """The set piece ended without being taken (restart timeout, an operator's stop): nobody is its taker,
        so nobody can touch the ball twice."""
        self.armed = False
        self.taker = -1
        self.retouch = None

    # --- input (physics rate) -------------------------------------------------------------------------------
    def on_contacts(self, msg) -> None:
        step = int(msg.step)
        holder = msg.holder
        touching = msg.touching
        if (
            holder
            and not msg.kicker
            and not self.armed
            and (not touching or (len(touching) == 1 and touching[0] == holder))
        ):
            # the steady hold (most messages: the held ball sits in the mouth, mostly without a contact): the
            # robot that alone had the ball at the last step still holds it, as the team on the ball, in
            # possession; what `_contact` would change is then only the step and where the robot and the ball are
            i = self.obs.index.get(holder, -1)
            if (
                i >= 0
                and self.contact_step == step - 1
                and self.touch_step[i] == step - 1
                and self.last == i
                and self.possessor == i
                and self.contact == (i,)
                and self._seen[i]
                and self.team_on_ball == self.obs.team_ix[i]
            ):
                self.holder = i
                self.ball_at_contact = self.obs.ball_xy_now()
                self.contact_step = self.last_step = self.touch_step[i] = step
                self.touch_x[i], self.touch_y[i] = self.obs.xy_now(i)
                return
        self._contact(msg, step)

    def _contact(self, msg, step: int) -> None:
        """A ``ball_contacts`` message (of physics step ``step``), the general way."""
        index = self.obs.index
        robots = [index[nm] for nm in msg.touching if nm in index]
        for extra in (msg.holder, msg.kicker):
            if extra and extra in index and index[extra] not in robots:
                robots.append(index[extra])
        self.holder = index.get(msg.holder, -1) if msg.holder else -1
        if not robots:
            return
        ball = self.obs.ball_xy_now()
        if msg.kicker and msg.kicker in index:
            k = index[msg.kicker]
            self.kick = (k, step, *self.obs.xy_now(k))
        self._team_touches(robots, step, ball)
        self.ball_at_contact = ball
        self.contact = tuple(robots)
        self.contact_step = step
        xy_now = self.obs.xy_now
        for i in robots:
            self.last = i
            self.last_step = step
            self.touch_x[i], self.touch_y[i] = xy_now(i)
            self.touch_step[i] = step
            if not self._seen[i]:
                self._seen[i] = True
                self.since_restart.append(i)
            if self.armed:
                self._taker_touch(i, step)
        self._possession(robots)

    def _team_touches(self, robots: list[int], step: int, ball: tuple[float, float]) -> None:
        """Who is on the ball as a team, and whether a team-mate received it in the opponent half after a free
        roll (before `last`, `touch_step` and `ball_at_contact` are updated for this step)."""
        obs = self.obs
        bx, by = ball
        for i in robots:
            k = obs.team_ix[i]
            if k != self.team_on_ball:
                self.team_on_ball = k
                self.won_by[k] = i
                self.won_at[k] = ball
                self.won_own_half[k] = obs.attack_sign[i] * bx < 0.0
                self.passed[k] = False
                self.longest_roll[k] = 0.0
                continue
            if self.touch_step[i] >= step - 1 or self.last == i or self.last < 0 or obs.team_ix[self.last] != k:
                continue  # the same touch going on, or no pass from a team-mate
            if obs.attack_sign[i] * bx <= 0.0:
                continue  # received in its own half (or on the line)
            px, py = self.ball_at_contact
            roll = math.hypot(bx - px, by - py)
            self.longest_roll[k] = max(self.longest_roll[k], roll)
            if roll >= self.pass_roll:
                self.passed[k] = True

    def needs_pass(self, team_ix: int) -> bool:
        """RC-10.1.2: the team won the ball in its own half and no team-mate received it in the opponent half
        after a free roll since."""
        return self.team_on_ball == team_ix and self.won_own_half[team_ix] and not self.passed[team_ix]

    def _taker_touch(self, i: int, step: int) -> None:
        if self.taker < 0:
            self.taker = i
        elif i == self.taker:
            if not self.others_touched and self.retouch is None and step - self.taker_last_contact >= self.gap_steps:
                x, y = self.obs.xy_now(i)
                self.retouch = (step, x, y, step - self.taker_last_contact)
        else:
            self.others_touched = True
            self.armed = False
        if i == self.taker:
            self.taker_last_contact = step

    def _possession(self, robots: list[int]) -> None:
        if len(robots) == 1:
            j = robots[0]
            if j != self.possessor:
                self.possessor = j
                self.start_xy = self.prev_xy = self.obs.xy_now(j)
                self.backward = 0.0
        elif self.possessor not in robots:
            self.possessor = -1

    # --- control rate -----------------------------------------------------------------------------------
    def update_possession(self) -> None:
        """End a possession whose ball has gone, and add up the possessor's backward travel."""
        i = self.possessor
        if i < 0:
            return
        obs = self.obs
        x, y = obs.X[i], obs.Y[i]
        if math.hypot(obs.bx - x, obs.by - y) > self.release:
            self.possessor = -1
            return
        yaw = obs.yaw(i)
        dx, dy = x - self.prev_xy[0], y - self.prev_xy[1]
        along = dx * math.cos(yaw) + dy * math.sin(yaw)
        if along < 0.0:
            self.backward -= along
        self.prev_xy = (x, y)

    def touched_by(self, team_ix: int) -> list[int]:
        """Robots of team ``team_ix`` that touched the ball since the restart, in order."""
        t = self.obs.team_ix
        return [i for i in self.since_restart if t[i] == team_ix]
