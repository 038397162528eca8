"""Each robot's perception (the paper's OmniVisionInfo), computed for all robots at once.

A robot sees the ball (position, velocity, and its bearing and distance from the robot's kicker axis),
every other robot as an obstacle, and its own team's robots (as its team shares them). Everything is in
the robot's team frame: the world frame for a team that attacks +x, the world turned by pi for the other
(magenta), so one strategy plays either colour. The frames turn when the teams change ends (`set_signs`).

Realism knobs from the scene, all off by default (and then the perception is exact): Gaussian noise on
positions, velocities and headings, the ball or an obstacle missed with a probability, and a latency
(the observation shows the world as it was that long ago). What a robot can see at all is `sight.Sight`'s
(obstacles in the line of sight, a drone camera's cone, a range). Heights (an aerial robot's altitude) are
given exactly.

The numbers are float32, as the messages define them (and as the original's were): they are rounded
here, where they are made, so that a strategy reads the same numbers whether its perception came through
the in-process bus (objects as built) or over the wire (decoded) — embedded and distributed runs decide
alike.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from itertools import islice, repeat

import numpy as np

from .. import msgs
from ..compiled import bind
from .kernels import Noise, perceive

# the messages' makers by position (see msgs.positional): every robot's messages are made at every tick
_BallInfo = msgs.positional(msgs.BallInfo, "state x y z vx vy vz angle distance pos_known velocity_known")
_ObstaclesInfo = msgs.positional(msgs.ObstaclesInfo, "x y vx vy angle distance radius z")
_RobotInfo = msgs.positional(msgs.RobotInfo, "id x y yaw vx vy w valid stuck holding_ball wheel_speeds z vz")
_OmniVisionInfo = msgs.positional(msgs.OmniVisionInfo, "stamp tick robot_id ball obstacles robots")
_F32 = np.float32


@dataclass
class Snapshot:
    """What the world looked like at one physics step (world frame)."""

    step: int
    robots: np.ndarray  # (N, 6): x y yaw vx vy w
    ball: np.ndarray  # (6,): x y z vx vy vz
    holder: int
    wheels: np.ndarray  # (N, W) rim speeds
    valid: np.ndarray  # (N,) bool
    stuck: np.ndarray  # (N,) bool
    heights: np.ndarray | None = None  # (N, 2): z, vz of each robot's origin (None: all on the ground)


class Perception:
    def __init__(
        self,
        robots,
        signs: np.ndarray,
        radii: np.ndarray,
        n_wheels: np.ndarray,
        spec,
        dt: float,
        rng: np.random.Generator,
        sight=None,
    ):
        self.n = len(robots)
        self.ids = np.array([r.rid for r in robots], dtype=np.int32)
        self.team_of = [r.team for r in robots]
        self.teams = list(dict.fromkeys(self.team_of))
        self.members = {t: [i for i in range(self.n) if self.team_of[i] == t] for t in self.teams}
        self.sign = signs.astype(float)
        self.radii = radii.astype(float)
        self.n_wheels = n_wheels
        self.spec = spec
        self.rng = rng
        self.delay_steps = int(round(spec.latency / dt))
        self.history: deque[Snapshot] = deque(maxlen=self.delay_steps + 1)
        n = self.n
        self.others = np.array([[j for j in range(n) if j != i] for i in range(n)], dtype=int).reshape(n, max(n - 1, 0))
        m = max(n - 1, 0)
        #: exact perception's noise: none
        self.noise_free = Noise(np.zeros((n, 5)), np.zeros((n, 4)), np.zeros((n, m, 4)))
        self._perceive = bind(perceive)
        self._orad = (self.radii[self.others] if n > 1 else np.zeros((n, 0))).astype(_F32)
        self._orad.setflags(write=False)  # its rows are in every tick's messages: nobody may change them
        self._orad_rows = list(self._orad)
        self._ids = self.ids.tolist()
        self.sight = sight  # what each robot can see at all (None: everything)
        self._ground_z = [0.0] * n
        self._oz = np.zeros((n, m), dtype=_F32)
        self._oz.setflags(write=False)
        self._oz_rows = list(self._oz)
        self._nw = [int(k) for k in n_wheels]
        # what `kernels.perceive` writes and the messages read into Python numbers, reused at every tick (no
        # message holds them; the arrays a message holds, obstacles and wheel speeds, are made fresh at every
        # tick): each robot's own state and the ball it sees, and, for `kernels.sense_ground`, the robots' and
        # the ball's world states and the robots' flags
        self.own32 = np.zeros((n, 6), dtype=_F32)
        self.balls32 = np.zeros((n, 8), dtype=_F32)
        self.R = np.zeros((n, 6))
        self.ball = np.zeros(6)
        self.valid = np.zeros(n, dtype=bool)
        self.stuck = np.zeros(n, dtype=bool)
        self._team_members = list(self.members.values())
        self._team_index = [self.teams.index(t) for t in self.team_of]
        self._nobody = [False] * n  # nobody holds the ball
        self._seen_state, self._seen = [1] * n, [True] * n  # a BallInfo's state, pos_known, velocity_known
        self._short_wheels = any(k != max(self._nw, default=0) for k in self._nw)
        self.exact = (
            spec.position_noise == 0
            and spec.velocity_noise == 0
            and spec.heading_noise == 0
            and spec.ball_dropout == 0
            and spec.obstacle_dropout == 0
        )

    def set_signs(self, signs: np.ndarray) -> None:
        """Every robot's team frame from now on (+1: the world frame, -1: the world turned by pi)."""
        self.sign[:] = signs

    @property
    def needs_history(self) -> bool:
        return self.delay_steps > 0

    def record(self, snap: Snapshot) -> None:
        self.history.append(snap)

    def delayed(self, now: Snapshot) -> Snapshot:
        if self.delay_steps == 0 or not self.history:
            return now
        return self.history[0]

    # -----------------------------------------------------------------------------------------------------
    def observe(self, snap: Snapshot, stamp: float, tick: int, only: list[int] | None = None) -> list:
        """One OmniVisionInfo per robot (in robot order); with ``only``, messages for those robots alone (None
        in the others' places: a real-time server takes each robot's perception at its own step). The noise
        is drawn for every robot either way."""
        n, m = self.n, max(self.n - 1, 0)
        noise = self.noise_free if self.exact else self._draw_noise()
        obs = np.empty((6 * n, m), dtype=_F32)  # fresh: the messages keep its rows
        self._perceive(snap.robots, snap.ball, self.sign, self.others, noise, self.own32, self.balls32, obs)
        spec, rng = self.spec, self.rng
        seen = None if spec.ball_dropout == 0 else (rng.random(n) >= spec.ball_dropout).tolist()
        keep = rng.random((n, m)) >= spec.obstacle_dropout if spec.obstacle_dropout > 0 and n > 1 else None
        if snap.heights is None:
            z = vz = self._ground_z
            oz = self._oz
        else:
            hz = snap.heights.astype(_F32)
            z, vz = hz[:, 0].tolist(), hz[:, 1].tolist()
            oz = hz[:, 0][self.others] if n > 1 else np.zeros((n, 0), dtype=_F32)
        if self.sight is not None:
            Z = snap.heights[:, 0] if snap.heights is not None else np.zeros(n)
            vis, ball_vis = self.sight.visible(snap.robots, Z, snap.ball, self.others)
            keep = vis if keep is None else keep & vis
            seen = ball_vis.tolist() if seen is None else [a and b for a, b in zip(seen, ball_vis.tolist())]
        wheels = [row[:k] for row, k in zip(snap.wheels.astype(_F32), self._nw)]
        out = self._messages(
            obs, wheels, snap.valid.tolist(), snap.stuck.tolist(), snap.holder, z, vz, oz, seen, keep, stamp, tick
        )
        if only is not None:
            wanted = set(only)
            out = [msg if i in wanted else None for i, msg in enumerate(out)]
        return out

    def observe_exact(self, obs: np.ndarray, wheels: np.ndarray, holder: int, stamp: float, tick: int) -> list:
        """`observe` of every robot for exact perception (no noise, no dropout, no sight rules, no latency),
        from the numbers `kernels.sense_ground` wrote: ``own32``, ``balls32``, ``valid``, ``stuck`` (this
        object's) and ``obs`` (n * 6, n - 1), ``wheels`` (n, W), fresh float32 arrays whose rows the messages
        keep."""
        # the rows by an iterator that stops at the last one (running an array's own iterator to its end makes
        # NumPy raise and catch an IndexError)
        rows = list(islice(wheels, self.n))
        if self._short_wheels:  # a robot with fewer wheels than the widest: its first ones
            rows = [r[:k] for r, k in zip(rows, self._nw)]
        z = self._ground_z
        return self._messages(
            obs, rows, self.valid.tolist(), self.stuck.tolist(), holder, z, z, self._oz, None, None, stamp, tick
        )

    def _messages(self, obs, wheels, valid, stuck, holder, z, vz, oz, seen, keep, stamp, tick) -> list:
        """Every robot's OmniVisionInfo from what `kernels.perceive` wrote (``own32``, ``balls32``, ``obs``) and
        the robots' flags: their wheel speeds' rows, valid, stuck, the ball's ``holder``, heights ``z``, ``vz``
        (n,) and the heights of the robots each sees ``oz`` (n, n-1); ``seen`` (n,) which robots see the
        ball (None: all) and ``keep`` (n, n-1) which robots each sees (None: all).

        The messages are made by `map` over per-field lists (numbers read in bulk by `tolist`): the message
        makers are called from C, with no bytecode per message."""
        n, ids = self.n, self._ids
        x, y, yaw, vx, vy, w = self.own32.T.tolist()
        holding = self._nobody.copy()
        if holder >= 0:
            holding[holder] = True
        infos = list(map(_RobotInfo, ids, x, y, yaw, vx, vy, w, valid, stuck, holding, wheels, z, vz))
        team_infos = [[infos[i] for i in idx] for idx in self._team_members]
        teams = map(team_infos.__getitem__, self._team_index)
        if keep is None:  # each robot's six rows, then the radii and heights of the robots it sees
            rows = iter(obs)
            oz_rows = self._oz_rows if oz is self._oz else list(oz)
            obstacles = map(_ObstaclesInfo, islice(rows, n), rows, rows, rows, rows, rows, self._orad_rows, oz_rows)
        else:  # each robot's rows of the robots it keeps, in one indexing
            stacked = np.concatenate((obs.reshape(n, 6, n - 1), self._orad[:, None], oz[:, None]), axis=1)
            obstacles = [_ObstaclesInfo(*stacked[i][:, keep[i]]) for i in range(n)]
        bx, by, bz, bvx, bvy, bvz, angle, distance = self.balls32.T.tolist()
        if seen is None:
            everyone = self._seen
            balls = map(_BallInfo, self._seen_state, bx, by, bz, bvx, bvy, bvz, angle, distance, everyone, everyone)
        else:
            unseen = _BallInfo(0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, False, False)
            balls = [
                _BallInfo(1, bx[i], by[i], bz[i], bvx[i], bvy[i], bvz[i], angle[i], distance[i], True, True)
                if seen[i]
                else unseen
                for i in range(n)
            ]
        return list(map(_OmniVisionInfo, repeat(stamp, n), repeat(tick, n), ids, balls, obstacles, teams))

    def _draw_noise(self) -> Noise:
        """This tick's noise on what each robot perceives, from the scene's standard deviations."""
        n, m = self.n, max(self.n - 1, 0)
        spec, rng = self.spec, self.rng
        pos, vel, head = spec.position_noise, spec.velocity_noise, spec.heading_noise
        noise = Noise(np.zeros((n, 5)), np.zeros((n, 4)), np.zeros((n, m, 4)))
        if pos > 0:  # own pose (self-localisation), the ball and every obstacle
            noise.own[:, :2] = rng.normal(0.0, pos, (n, 2))
            noise.ball[:, :2] = rng.normal(0.0, pos, (n, 2))
            noise.obstacles[:, :, :2] = rng.normal(0.0, pos, (n, m, 2))
        if head > 0:
            noise.own[:, 2] = rng.normal(0.0, head, n)
        if vel > 0:
            noise.own[:, 3:] = rng.normal(0.0, vel, (n, 2))
            noise.ball[:, 2:] = rng.normal(0.0, vel, (n, 2))
            noise.obstacles[:, :, 2:] = rng.normal(0.0, vel, (n, m, 2))
        return noise
