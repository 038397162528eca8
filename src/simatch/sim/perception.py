"""Each robot's perception (the paper's OmniVisionInfo), computed for all robots at once.

A robot sees the ball (position, velocity, and its bearing and distance from the robot's kicker axis),
every other robot as an obstacle, and its own team's robots (as its team shares them). Everything is in
the robot's team frame: the world frame for a team that attacks +x, the world turned by pi for the other
(magenta), so one strategy plays either colour.

Realism knobs from the scene, all off by default (and then the perception is exact): Gaussian noise on
positions, velocities and headings, the ball or an obstacle missed with a probability, and a latency
(the observation shows the world as it was that long ago).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from .. import msgs
from .kernels import perceive

_BallInfo = msgs.BallInfo
_ObstaclesInfo = msgs.ObstaclesInfo
_RobotInfo = msgs.RobotInfo
_OmniVisionInfo = msgs.OmniVisionInfo
_EMPTY = np.zeros(0)


@dataclass
class Snapshot:
    """What the world looked like at one physics step (world frame)."""

    step: int
    robots: np.ndarray      # (N, 6): x y yaw vx vy w
    ball: np.ndarray        # (6,): x y z vx vy vz
    holder: int
    wheels: np.ndarray      # (N, W) rim speeds
    valid: np.ndarray       # (N,) bool
    stuck: np.ndarray       # (N,) bool


def wrap(a):
    """Angle(s) wrapped to [-pi, pi)."""
    return (a + np.pi) % (2 * np.pi) - np.pi


class Perception:
    def __init__(self, robots, signs: np.ndarray, radii: np.ndarray, n_wheels: np.ndarray, spec, dt: float,
                 rng: np.random.Generator):
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
        self._turn = np.where(self.sign > 0, 0.0, np.pi)
        m = max(n - 1, 0)
        self._no_own_noise, self._no_ball_noise, self._no_obs_noise = np.zeros((n, 5)), np.zeros((n, 4)), np.zeros((n, m, 4))
        self._orad = self.radii[self.others] if n > 1 else np.zeros((n, 0))
        self._ids = self.ids.tolist()
        self._nw = [int(k) for k in n_wheels]
        self.exact = (spec.position_noise == 0 and spec.velocity_noise == 0 and spec.heading_noise == 0
                      and spec.ball_dropout == 0 and spec.obstacle_dropout == 0)

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
    def observe(self, snap: Snapshot, stamp: float, tick: int) -> list:
        """One OmniVisionInfo per robot (in robot order)."""
        n = self.n
        spec, rng = self.spec, self.rng
        m = max(n - 1, 0)
        own_noise, ball_noise, obs_noise = self._no_own_noise, self._no_ball_noise, self._no_obs_noise
        if not self.exact:
            pos, vel, head = spec.position_noise, spec.velocity_noise, spec.heading_noise
            own_noise = np.zeros((n, 5))
            ball_noise = np.zeros((n, 4))
            obs_noise = np.zeros((n, m, 4))
            if pos > 0:        # own pose (self-localisation), the ball and every obstacle
                own_noise[:, :2] = rng.normal(0.0, pos, (n, 2))
                ball_noise[:, :2] = rng.normal(0.0, pos, (n, 2))
                obs_noise[:, :, :2] = rng.normal(0.0, pos, (n, m, 2))
            if head > 0:
                own_noise[:, 2] = rng.normal(0.0, head, n)
            if vel > 0:
                own_noise[:, 3:] = rng.normal(0.0, vel, (n, 2))
                ball_noise[:, 2:] = rng.normal(0.0, vel, (n, 2))
                obs_noise[:, :, 2:] = rng.normal(0.0, vel, (n, m, 2))
        own, balls, obs = perceive(snap.robots, snap.ball, self.sign, self.others, own_noise, ball_noise, obs_noise)
        seen = [True] * n if spec.ball_dropout == 0 else (rng.random(n) >= spec.ball_dropout).tolist()
        keep = None
        if spec.obstacle_dropout > 0 and n > 1:
            keep = rng.random((n, m)) >= spec.obstacle_dropout

        # per-robot numbers as Python floats, converted in bulk (building messages from numpy scalars is slow)
        tx, ty, tyaw, tvx, tvy, tw = own.T.tolist()
        valid, stuck = snap.valid.tolist(), snap.stuck.tolist()
        wheels = snap.wheels
        ids = self._ids
        team_infos = {}
        for team, idx in self.members.items():
            team_infos[team] = [_RobotInfo(
                id=ids[i], x=tx[i], y=ty[i], yaw=tyaw[i], vx=tvx[i], vy=tvy[i], w=tw[i], valid=valid[i],
                stuck=stuck[i], holding_ball=snap.holder == i, wheel_speeds=wheels[i, : self._nw[i]])
                for i in idx]
        tx_o, ty_o, tvx_o, tvy_o, o_ang, o_dist = obs
        orad = self._orad
        sx, sy, svx, svy, bang, bdist = balls.T.tolist()
        seen_l = seen
        bz, bvz = float(snap.ball[2]), float(snap.ball[5])
        out = []
        for i in range(n):
            if seen_l[i]:
                ball = _BallInfo(state=1, x=sx[i], y=sy[i], z=bz, vx=svx[i], vy=svy[i], vz=bvz, angle=bang[i],
                                 distance=bdist[i], pos_known=True, velocity_known=True)
            else:
                ball = _BallInfo(state=0, x=0.0, y=0.0, z=0.0, vx=0.0, vy=0.0, vz=0.0, angle=0.0, distance=0.0,
                                 pos_known=False, velocity_known=False)
            if n > 1:
                if keep is None:
                    obstacles = _ObstaclesInfo(x=tx_o[i], y=ty_o[i], vx=tvx_o[i], vy=tvy_o[i], angle=o_ang[i],
                                               distance=o_dist[i], radius=orad[i])
                else:
                    sel = keep[i]
                    obstacles = _ObstaclesInfo(x=tx_o[i][sel], y=ty_o[i][sel], vx=tvx_o[i][sel], vy=tvy_o[i][sel],
                                               angle=o_ang[i][sel], distance=o_dist[i][sel], radius=orad[i][sel])
            else:
                obstacles = _ObstaclesInfo(x=_EMPTY, y=_EMPTY, vx=_EMPTY, vy=_EMPTY, angle=_EMPTY,
                                           distance=_EMPTY, radius=_EMPTY)
            out.append(_OmniVisionInfo(stamp=stamp, tick=tick, robot_id=ids[i], ball=ball,
                                       obstacles=obstacles, robots=team_infos[self.team_of[i]]))
        return out

