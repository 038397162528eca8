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
        R = snap.robots
        px, py, yaw, vx, vy, w = (R[:, k] for k in range(6))
        bx, by, bz, bvx, bvy, bvz = snap.ball
        s = self.sign

        # own pose as each robot believes it (self-localisation noise)
        if spec.position_noise > 0:
            px = px + rng.normal(0.0, spec.position_noise, n)
            py = py + rng.normal(0.0, spec.position_noise, n)
        if spec.heading_noise > 0:
            yaw = yaw + rng.normal(0.0, spec.heading_noise, n)
        if spec.velocity_noise > 0:
            vx = vx + rng.normal(0.0, spec.velocity_noise, n)
            vy = vy + rng.normal(0.0, spec.velocity_noise, n)
        yaw_team = wrap(yaw + self._turn)

        # per-robot numbers as Python floats, converted in bulk (building messages from numpy scalars is slow)
        tx, ty, tyaw = (s * px).tolist(), (s * py).tolist(), yaw_team.tolist()
        tvx, tvy, tw = (s * vx).tolist(), (s * vy).tolist(), w.tolist()
        valid, stuck = snap.valid.tolist(), snap.stuck.tolist()
        wheels = snap.wheels
        ids = self._ids
        team_infos = {}
        for team, idx in self.members.items():
            team_infos[team] = [_RobotInfo(
                id=ids[i], x=tx[i], y=ty[i], yaw=tyaw[i], vx=tvx[i], vy=tvy[i], w=tw[i], valid=valid[i],
                stuck=stuck[i], holding_ball=snap.holder == i, wheel_speeds=wheels[i, : self._nw[i]])
                for i in idx]

        # ball seen by each robot
        bxs = np.full(n, bx)
        bys = np.full(n, by)
        bvxs = np.full(n, bvx)
        bvys = np.full(n, bvy)
        if spec.position_noise > 0:
            bxs = bxs + rng.normal(0.0, spec.position_noise, n)
            bys = bys + rng.normal(0.0, spec.position_noise, n)
        if spec.velocity_noise > 0:
            bvxs = bvxs + rng.normal(0.0, spec.velocity_noise, n)
            bvys = bvys + rng.normal(0.0, spec.velocity_noise, n)
        seen = np.ones(n, dtype=bool) if spec.ball_dropout == 0 else rng.random(n) >= spec.ball_dropout
        bdx, bdy = bxs - px, bys - py
        b_ang = wrap(np.arctan2(bdy, bdx) - yaw)
        b_dist = np.hypot(bdx, bdy)

        # obstacles: every other robot, true positions seen from each (noisy) observer
        o = self.others
        ox, oy = R[:, 0][o], R[:, 1][o]                 # (n, n-1) world
        ovx, ovy = R[:, 3][o], R[:, 4][o]
        if spec.position_noise > 0 and n > 1:
            ox = ox + rng.normal(0.0, spec.position_noise, ox.shape)
            oy = oy + rng.normal(0.0, spec.position_noise, oy.shape)
        if spec.velocity_noise > 0 and n > 1:
            ovx = ovx + rng.normal(0.0, spec.velocity_noise, ovx.shape)
            ovy = ovy + rng.normal(0.0, spec.velocity_noise, ovy.shape)
        odx, ody = ox - px[:, None], oy - py[:, None]
        o_ang = wrap(np.arctan2(ody, odx) - yaw[:, None])
        o_dist = np.hypot(odx, ody)
        sc = s[:, None]
        tx_o, ty_o, tvx_o, tvy_o = sc * ox, sc * oy, sc * ovx, sc * ovy
        orad = self.radii[o]
        keep = None
        if spec.obstacle_dropout > 0 and n > 1:
            keep = rng.random(ox.shape) >= spec.obstacle_dropout

        sx, sy, svx, svy = (s * bxs).tolist(), (s * bys).tolist(), (s * bvxs).tolist(), (s * bvys).tolist()
        bang, bdist, seen_l = b_ang.tolist(), b_dist.tolist(), seen.tolist()
        bz, bvz = float(bz), float(bvz)
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

