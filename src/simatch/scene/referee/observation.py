"""What the referee sees: the exact model states from the simulation interface.

The referee is fed only by topics (``model_states`` every physics step, ``ball_contacts`` when something
touches the ball), so it judges a live run and a replayed recording alike. `Observation` keeps the latest
ModelStates message (a reference, no copy, every physics step) and, once per control period, `refresh`
turns it into plain Python lists: the rules' arithmetic over ten robots is on plain floats, not on many
small NumPy arrays. It also knows what never changes during a match: who is in which
team, which robot keeps goal. Which way each team attacks is known too, and changes when the teams change
ends (`set_sign`): every rule reads it here, at the time it judges.
"""

from __future__ import annotations

import math

import numpy as np

from ...bus import topics


class Observation:
    def __init__(self, scene, robot_radius: float):
        spec = scene.spec
        self.teams: list[str] = list(spec.teams)
        self.sign = {t: spec.team_sign(t) for t in self.teams}  # +1: attacks +x (now)
        self.scene_sign = dict(self.sign)  # as the scene sets it (the first half's)
        self.field = f = spec.world.geometry()
        self.ball_radius = spec.ball.radius
        names = spec.robot_names()
        self.names: list[str] = names
        self.n = n = len(names)
        self.index = {name: i for i, name in enumerate(names)}
        split = [topics.split_robot_name(nm) for nm in names]
        self.team_of: list[str] = [t for t, _ in split]
        self.rid: list[int] = [r for _, r in split]
        self.team_ix: list[int] = [self.teams.index(t) for t in self.team_of]
        self.attack_sign: list[int] = [self.sign[t] for t in self.team_of]
        self.own_side: list[int] = [-s for s in self.attack_sign]  # side of the goal each robot defends
        self.is_goalkeeper: list[bool] = [spec.teams[t].goalkeeper == r for t, r in split]
        self.radius: list[float] = [float(spec.teams[t].model_params.get("radius", robot_radius)) for t in self.team_of]
        self.members: dict[str, list[int]] = {t: [i for i in range(n) if self.team_of[i] == t] for t in self.teams}
        self.active: list[bool] = [True] * n  # not sent off
        # area bounds, the painted lines included: |x| >= *_x and |y| <= *_y (the areas extend behind the
        # goal line)
        self._pen_x, self._pen_y = f.area_limits("penalty")
        self._goal_x, self._goal_y = f.area_limits("goal")
        self.msg = None
        self._rows: list[int] | None = None  # message row of each robot and of the ball
        self._in_order = False
        self._near = min(self._pen_x, self._goal_x)  # nearer the half-way line than this, no robot is in an area
        self.stamp = 0.0
        self.step = -1
        self.X = [0.0] * n
        self.Y = [0.0] * n
        self.VX = [0.0] * n
        self.VY = [0.0] * n
        self.bx = self.by = self.bz = 0.0
        self.bvx = self.bvy = self.bvz = 0.0
        self.bwx = self.bwy = 0.0  # the ball's spin about the horizontal axes, world frame [rad/s]
        self.penalty_area = [0] * n  # side of the penalty area the robot is in (-1, +1), 0 if none
        self.goal_area = [0] * n

    def set_sign(self, team: str, sign: int) -> None:
        """``team`` attacks +x (``sign`` +1) or -x (-1) from now on: the teams changed ends."""
        self.sign[team] = sign
        for i in self.members[team]:
            self.attack_sign[i] = sign
            self.own_side[i] = -sign

    def attacks(self, team: str) -> str:
        return "+x" if self.sign[team] > 0 else "-x"

    # --- input -------------------------------------------------------------------------------------------
    def set_message(self, msg) -> None:
        """The latest ModelStates (every physics step: keeps a reference only)."""
        self.msg = msg

    def refresh(self) -> None:
        """Read the latest message into lists and classify every robot's area (once per control period)."""
        msg = self.msg
        if self._rows is None:
            self._locate(msg)
        pose, twist = msg.pose, msg.twist
        rows = self._rows
        n = self.n
        X, Y, VX, VY = self.X, self.Y, self.VX, self.VY
        if self._in_order:  # the same lists, filled in place (a rule may hold them)
            # only the numbers the rules read become Python floats, taken through strided views
            X[:] = pose[0 : 7 * n : 7].tolist()
            Y[:] = pose[1 : 7 * n : 7].tolist()
            VX[:] = twist[0 : 6 * n : 6].tolist()
            VY[:] = twist[1 : 6 * n : 6].tolist()
            self.bx, self.by, self.bz = pose[7 * n : 7 * n + 3].tolist()
            self.bvx, self.bvy, self.bvz, self.bwx, self.bwy = twist[6 * n : 6 * n + 5].tolist()
        else:
            P = pose.tolist()
            T = twist.tolist()
            for i in range(n):
                r = rows[i]
                X[i] = P[7 * r]
                Y[i] = P[7 * r + 1]
                VX[i] = T[6 * r]
                VY[i] = T[6 * r + 1]
            b = rows[n]
            self.bx, self.by, self.bz = P[7 * b], P[7 * b + 1], P[7 * b + 2]
            self.bvx, self.bvy, self.bvz = T[6 * b], T[6 * b + 1], T[6 * b + 2]
            self.bwx, self.bwy = T[6 * b + 3], T[6 * b + 4]
        pen, goal = self.penalty_area, self.goal_area
        px, py, gx, gy, near = self._pen_x, self._pen_y, self._goal_x, self._goal_y, self._near
        far = -near  # (negated once, not for every robot)
        for i in range(n):
            x = X[i]
            if far < x < near:  # short of both areas (the usual case)
                pen[i] = goal[i] = 0
                continue
            y = Y[i]
            ax, ay = abs(x), abs(y)
            side = 1 if x > 0 else -1
            pen[i] = side if ax >= px and ay <= py else 0
            goal[i] = side if ax >= gx and ay <= gy else 0
        self.stamp = msg.stamp
        self.step = msg.step

    def _locate(self, msg) -> None:
        """Find each robot's and the ball's row in the messages (the same in every message of a run)."""
        self._rows = self._find_rows(list(msg.name))
        # in the simulator's order (robots, then the ball) every column is read by one slice of the lists
        self._in_order = self._rows == list(range(self.n + 1))

    def _find_rows(self, names: list[str]) -> list[int]:
        expected = self.names + ["ball"]
        missing = [nm for nm in expected if nm not in names]
        if missing:
            raise ValueError(f"model_states lacks {', '.join(missing)}")
        return [names.index(nm) for nm in expected]

    def ball_row(self) -> int:
        if self._rows is None:
            self._locate(self.msg)
        return self._rows[self.n]

    def xy_now(self, i: int) -> tuple[float, float]:
        """Robot i's position in the latest message (physics rate, without a refresh)."""
        if self._rows is None:
            self._locate(self.msg)
        r = 7 * self._rows[i]
        item = self.msg.pose.item  # (a plain float at once, no NumPy scalar: read at every touch of the ball)
        return (float(item(r)), float(item(r + 1)))

    def ball_xy_now(self) -> tuple[float, float]:
        """The ball's position in the latest message (physics rate, without a refresh)."""
        if self._rows is None:
            self._locate(self.msg)
        r = 7 * self._rows[self.n]
        item = self.msg.pose.item
        return (float(item(r)), float(item(r + 1)))

    # --- geometry ----------------------------------------------------------------------------------------
    def yaw(self, i: int) -> float:
        r = 7 * self._rows[i]
        item = self.msg.pose.item  # (plain floats, no NumPy scalars: the same numbers)
        return 2.0 * math.atan2(item(r + 6), item(r + 3))

    def ball_distance(self, i: int) -> float:
        return math.hypot(self.X[i] - self.bx, self.Y[i] - self.by)

    def distance_to(self, i: int, x: float, y: float) -> float:
        return math.hypot(self.X[i] - x, self.Y[i] - y)

    @property
    def xy(self) -> np.ndarray:
        """(N, 2) robot positions as of the last refresh."""
        return np.column_stack((self.X, self.Y))

    def own_goal_side(self, team: str) -> int:
        """-1 if the team defends the goal at -x (cyan), +1 otherwise."""
        return -self.sign[team]

    def defender_of(self, side: int) -> str:
        """The team whose goal is at ``side``."""
        return self.teams[0] if -self.sign[self.teams[0]] == side else self.teams[1]

    def other(self, team: str) -> str:
        """The opponent of ``team`` (two-team matches)."""
        return self.teams[1] if team == self.teams[0] else self.teams[0]

    def in_opponent_half(self, i: int, x: float) -> bool:
        """Robot i at ``x`` is strictly past the half-way line, towards its attack."""
        return self.attack_sign[i] * x > 0.0
