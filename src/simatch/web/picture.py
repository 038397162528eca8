"""The pictures the pages draw, as JSON-able dicts built from what the `RunObserver` gathered.

* `Picture.world(i)`: the exact world at Timeline sample ``i`` (referee console, replay page): every
  robot and the ball, with the game state of that moment.
* `Picture.team(team, t)`: what one team knows at time ``t`` (its coach page): its robots as they
  perceive themselves, with their wheel speeds, role, action and flags; the obstacles each one sees;
  the ball as seen by the robot nearest to it (as the original coach fused it); pass lines; the command
  the team is playing.

Everything is in the world frame; a team's perception is turned back from its team frame here, the frame
the team had at that moment (the game state says which way each team attacks: the teams change ends at
half time).
"""

from __future__ import annotations

import math

from .. import frames
from ..msgs.game_commands import name as command_name
from ..robots import model_class
from ..robots.looks import member_looks
from ..strategy.roles import action_words, role_words
from .observer import RunObserver


def _r(v: float, digits: int = 3) -> float | None:
    v = float(v)
    return round(v, digits) if math.isfinite(v) else None


class Picture:
    def __init__(self, observer: RunObserver, spec, sent_off=lambda: ()):
        self.obs = observer
        self.spec = spec
        self.teams = list(spec.teams)
        self.signs = {team: spec.team_sign(team) for team in self.teams}
        self.ids = {team: spec.teams[team].robot_ids() for team in self.teams}
        self.sent_off = sent_off
        #: the aerial robots (name -> model), drawn with their height
        self.aerial = {
            f"{team}/{m.id}": model_class(m.model)(m.model_params)
            for team in self.teams
            for m in spec.teams[team].members()
            if model_class(m.model).locomotion == "aerial"
        }

    def robots_meta(self) -> list[dict]:
        """Each robot as the pages draw it: its team, id, footprint radius, and its body (`simatch.robots.looks`:
        the one description of a body that the recordings' 3D scene draws too)."""
        out = []
        for team in self.teams:
            spec = self.spec.teams[team]
            for m in spec.members():
                name = f"{team}/{m.id}"
                body = member_looks(m)
                meta = {
                    "name": name,
                    "team": team,
                    "id": m.id,
                    "radius": body["radius"],
                    "goalkeeper": m.id == spec.goalkeeper,
                    "body": body,
                }
                flyer = self.aerial.get(name)
                if flyer is not None:
                    meta.update(aerial=True, model=flyer.name, goalkeeper=False)
                out.append(meta)
        return out

    def _off(self, game: dict | None) -> list[str]:
        return sorted(set(self.sent_off()) | set(game["sent_off"] if game else ()))

    def _commands(self) -> dict:
        out = {}
        for team, info in list(self.obs.coach.items()):
            out[team] = {
                "mode": command_name(info.match_mode),
                "type": command_name(info.match_type),
                "max_vel": _r(info.max_vel, 2),
                "max_w": _r(info.max_w, 2),
            }
        return out

    # --- the exact world ----------------------------------------------------------------------------------
    def world(self, i: int, live: bool = False) -> dict:
        """The exact world at Timeline sample ``i``; ``live`` adds what only the present has (each robot's
        cards so far)."""
        tl = self.obs.timeline
        t = tl.time(i)
        s = tl.sample(i)
        robots, ball = [], None
        for k, name in enumerate(tl.names):
            x, y, z, yaw, vx, vy = (float(v) for v in s[k])
            if name == "ball":
                ball = {"x": _r(x), "y": _r(y), "z": _r(z), "vx": _r(vx, 2), "vy": _r(vy, 2)}
            else:
                team, _, rid = name.partition("/")
                robot = {
                    "name": name,
                    "team": team,
                    "id": int(rid),
                    "x": _r(x),
                    "y": _r(y),
                    "yaw": _r(yaw),
                    "vx": _r(vx, 2),
                    "vy": _r(vy, 2),
                }
                if name in self.aerial:
                    robot["z"] = _r(z)
                robots.append(robot)
        game = self.obs.game_at(t)
        out = {
            "type": "frame",
            "t": _r(t),
            "robots": robots,
            "ball": ball,
            "game": game,
            "commands": self._commands(),
            "sent_off": self._off(game),
        }
        if live:
            out["cards"] = {name: list(c) for name, c in list(self.obs.cards.items())}
        return out

    # --- what one team knows --------------------------------------------------------------------------------
    def frame_sign(self, team: str, stamp: float) -> int:
        """+1 if ``team``'s frame was the world frame for what its robots perceived at ``stamp``, -1 if it was
        turned by pi. A perception is made before the judge's step at the same time, so the game state
        that changed the ends at ``stamp`` applies from the next perception on."""
        game = self.obs.game_at(stamp - 1e-6)
        side = (game or {}).get("attacks", {}).get(team)
        return self.signs[team] if side is None else (-1 if side == "-x" else 1)

    def team(self, team: str, t: float) -> dict:
        """What ``team`` knows at ``t``: each robot as it perceives itself and what it intends, the obstacles
        each one sees, the ball as seen by the robot nearest to it, the pass lines, the team's command."""
        robots, obstacles, passes = [], {}, []
        best_ball, best_dist = None, math.inf
        game = self.obs.game_at(t)
        off = set(self._off(game))
        for rid in self.ids[team]:
            vision = self.obs.vision_at(team, rid, t)
            intent = self.obs.intent_at(team, rid, t)
            sign = self.frame_sign(team, float(vision.stamp) if vision is not None else t)
            entry: dict = {"id": rid, "name": f"{team}/{rid}", "sent_off": f"{team}/{rid}" in off, "seen": False}
            me = _myself(vision, rid)
            if me is not None:
                entry.update(self._as_seen(me, sign, entry["name"]))
                obstacles[rid] = self._obstacles(vision, sign, team)
                b = vision.ball
                if b.pos_known and b.distance < best_dist:
                    best_dist = b.distance
                    best_ball = _ball_seen(b, sign, rid)
            if intent is not None:
                entry.update(_intention(intent, sign))
                p = intent.pass_cmd
                if p.is_valid and me is not None:
                    passes.append(_pass_line(p, sign, rid, entry))
            robots.append(entry)
        return {
            "type": "frame",
            "t": _r(t),
            "team": team,
            "robots": robots,
            "ball": best_ball,
            "obstacles": obstacles,
            "passes": passes,
            "command": self._team_command(team),
            "game": game,
        }

    def _as_seen(self, me, sign: int, name: str) -> dict:
        """A robot as it perceives itself, in the world frame."""
        x, y = frames.point(sign, me.x, me.y)
        vx, vy = frames.point(sign, me.vx, me.vy)
        seen = dict(
            seen=True,
            x=_r(x),
            y=_r(y),
            yaw=_r(frames.yaw(sign, me.yaw)),
            vx=_r(vx, 2),
            vy=_r(vy, 2),
            w=_r(me.w, 2),
            speed=_r(math.hypot(me.vx, me.vy), 2),
            wheels=[_r(u, 2) for u in me.wheel_speeds],
            valid=bool(me.valid),
            stuck=bool(me.stuck),
            holding=bool(me.holding_ball),
        )
        if name in self.aerial:
            seen.update(z=_r(me.z), vz=_r(me.vz, 2))
        return seen

    def _team_command(self, team: str) -> dict | None:
        """The command ``team`` is playing (its latest CoachInfo), None before the first."""
        info = self.obs.coach.get(team)
        if info is None:
            return None
        return {
            "mode": command_name(info.match_mode),
            "type": command_name(info.match_type),
            "test_mode": int(info.test_mode),
            "max_vel": _r(info.max_vel, 2),
            "max_w": _r(info.max_w, 2),
        }

    @staticmethod
    def _obstacles(vision, sign: int, team: str) -> list[list[float]]:
        o = vision.obstacles
        out = []
        mates = [(r.x, r.y) for r in vision.robots]
        for k in range(len(o.x)):
            ox, oy = float(o.x[k]), float(o.y[k])
            if any(math.hypot(ox - mx, oy - my) < 0.1 for mx, my in mates):
                continue  # a teammate, not an obstacle to avoid (as the original's oppinfo)
            wx, wy = frames.point(sign, ox, oy)
            seen = [_r(wx), _r(wy), _r(float(o.radius[k]) if len(o.radius) > k else 0.25, 2)]
            if len(o.z) > k and o.z[k] > 0.05:
                seen.append(_r(float(o.z[k]), 2))  # a drone: its height
            out.append(seen)
        return out


def _myself(vision, rid: int):
    """Robot ``rid``'s perception of itself in its vision message (None: no message, or not in it)."""
    if vision is None:
        return None
    for r in vision.robots:
        if r.id == rid:
            return r
    return None


def _ball_seen(b, sign: int, rid: int) -> dict:
    """The ball as robot ``rid`` sees it, in the world frame."""
    bx, by = frames.point(sign, b.x, b.y)
    bvx, bvy = frames.point(sign, b.vx, b.vy)
    return {"x": _r(bx), "y": _r(by), "z": _r(b.z), "vx": _r(bvx, 2), "vy": _r(bvy, 2), "seen_by": rid}


def _intention(intent, sign: int) -> dict:
    """What a robot intends: its role, action, whether it dribbles, and its target (world frame) if it has one."""
    out = dict(role=role_words(intent.role), action=action_words(intent.action), dribble=bool(intent.is_dribble))
    tx, ty = float(intent.target_x), float(intent.target_y)
    if math.isfinite(tx) and math.isfinite(ty):
        wx, wy = frames.point(sign, tx, ty)
        out["target"] = [_r(wx), _r(wy)]
    return out


def _pass_line(p, sign: int, rid: int, passer: dict) -> dict:
    """A pass robot ``rid`` plays or prepares: from where it stands to the catch point."""
    cx, cy = frames.point(sign, p.catch_x, p.catch_y)
    return {
        "passer": rid,
        "catcher": int(p.catch_id),
        "from": [passer["x"], passer["y"]],
        "to": [_r(cx), _r(cy)],
        "kicked": bool(p.is_passout),
    }
