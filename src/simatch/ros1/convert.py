"""simatch's messages and the original's, both ways: SI on simatch's bus, the original's centimetres, names
and numbering on ROS (simatch-original.md 2.1, 3, 5.5).

Perception, commands and game commands are in the team frame on both sides (simatch mirrors magenta's
world exactly as the original's plugin did), so only units and field layouts change here; the world
(``/gazebo/model_states``) is in the world frame and metres on both sides, as gazebo_ros publishes it.

Messages on the ROS side are made through a *kit* (`Kit`): the live bridge uses the classes genpy generated
(rospy), the bag writer rosbags' type store; the conversions are the same code for both.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import Any, Protocol

import numpy as np

from .. import msgs
from ..msgs.game_commands import MatchMode
from .names import Names, Robot

CM = 100.0  # centimetres per metre
#: the original's Actions enum (core.hpp): the value meaning "no motion" in ActionCmd.move_action
NO_ACTION = 21
RUN, FLY = 1, -1  # ActionCmd.shootPos: ground kick, lob
#: CoachInfo.angleA/angleB outside test mode: the speed and turn-rate limits the referee always sent
REFEREE_MAX_VEL_CM, REFEREE_MAX_W = 450, 10


class Kit(Protocol):
    """Makes the original's messages: ``make("nubot_common/VelCmd", Vx=..., ...)`` with every field given,
    ``header(seq, stamp)`` (std_msgs/Header) and ``time(stamp)`` (a ROS time) from simulated seconds."""

    def make(self, msgtype: str, **fields: Any) -> Any: ...

    def header(self, seq: int, stamp: float, frame_id: str = "") -> Any: ...

    def time(self, stamp: float) -> Any: ...


def stamp_ns(stamp: float) -> tuple[int, int]:
    """Simulated seconds as (secs, nsecs), rounded to the nanosecond."""
    ns = round(float(stamp) * 1e9)
    return ns // 1_000_000_000, ns % 1_000_000_000


def _i16(value: float) -> int:
    return int(max(-32768, min(32767, round(value)))) if math.isfinite(value) else 0


def _u8(value: float) -> int:
    return int(max(0, min(255, round(value)))) if math.isfinite(value) else 0


# --- simatch -> ROS ------------------------------------------------------------------------------------------
def point(kit: Kit, x: float, y: float) -> Any:
    return kit.make("nubot_common/Point2d", x=float(x) * CM, y=float(y) * CM)


def ball_info(kit: Kit, ball: Any, header: Any) -> Any:
    return kit.make(
        "nubot_common/BallInfo",
        header=header,
        ballinfostate=int(ball.state),
        pos=point(kit, ball.x, ball.y),
        real_pos=kit.make("nubot_common/PPoint", angle=float(ball.angle), radius=float(ball.distance) * CM),
        velocity=point(kit, ball.vx, ball.vy),
        pos_known=bool(ball.pos_known),
        velocity_known=bool(ball.velocity_known),
    )


def obstacles_info(kit: Kit, obs: Any, header: Any) -> Any:
    xs, ys = np.asarray(obs.x, dtype=float) * CM, np.asarray(obs.y, dtype=float) * CM
    angles, dists = np.asarray(obs.angle, dtype=float), np.asarray(obs.distance, dtype=float) * CM
    return kit.make(
        "nubot_common/ObstaclesInfo",
        header=header,
        pos=[kit.make("nubot_common/Point2d", x=float(x), y=float(y)) for x, y in zip(xs, ys)],
        polar_pos=[kit.make("nubot_common/PPoint", angle=float(a), radius=float(d)) for a, d in zip(angles, dists)],
    )


def robot_info(kit: Kit, r: Any, header: Any) -> Any:
    return kit.make(
        "nubot_common/RobotInfo",
        header=header,
        AgentID=int(r.id),
        targetNum1=0,
        targetNum2=0,
        targetNum3=0,
        targetNum4=0,
        staticpassNum=0,
        staticcatchNum=0,
        pos=point(kit, r.x, r.y),
        heading=kit.make("nubot_common/Angle", theta=float(r.yaw)),
        vrot=float(r.w),
        vtrans=point(kit, r.vx, r.vy),
        iskick=False,
        isvalid=bool(r.valid),
        isstuck=bool(r.stuck),
        isdribble=bool(r.holding_ball),
        current_role=0,
        role_time=0.0,
        target=kit.make("nubot_common/Point2d", x=0.0, y=0.0),
    )


def omnivision(kit: Kit, msg: Any, seq: int) -> Any:
    """simatch's OmniVisionInfo of one robot as the original's OminiVisionInfo (cm, cm/s, rad)."""
    header = kit.header(seq, msg.stamp)
    return kit.make(
        "nubot_common/OminiVisionInfo",
        header=header,
        ballinfo=ball_info(kit, msg.ball, header),
        obstacleinfo=obstacles_info(kit, msg.obstacles, header),
        robotinfo=[robot_info(kit, r, header) for r in msg.robots],
    )


def holding(msg: Any) -> bool:
    """Whether the perceiving robot holds the ball (its own entry in its OmniVisionInfo)."""
    for r in msg.robots:
        if r.id == msg.robot_id:
            return bool(r.holding_ball)
    return False


def ball_is_holding(kit: Kit, held: bool) -> Any:
    return kit.make("nubot_common/BallIsHolding", BallIsHolding=1 if held else 0)


def coach_info(kit: Kit, msg: Any, seq: int, stamp: float) -> Any:
    """A team's game command as the original's CoachInfo: MatchMode/MatchType with the original numbering;
    outside test mode angleA/angleB carry the speed limit [cm/s] and turn-rate limit [rad/s] (the
    referee's 450 and 10 when none is set); in test mode the test's points [cm], angles [deg], robots and
    kick force."""
    test = int(msg.match_mode) == MatchMode.TEST
    if test:
        angle_a, angle_b = math.degrees(msg.angle_a), math.degrees(msg.angle_b)
    else:
        angle_a = msg.max_vel * CM if msg.max_vel > 0 else REFEREE_MAX_VEL_CM
        angle_b = msg.max_w if msg.max_w > 0 else REFEREE_MAX_W
    return kit.make(
        "nubot_common/CoachInfo",
        header=kit.header(seq, stamp),
        MatchMode=_u8(msg.match_mode),
        MatchType=_u8(msg.match_type),
        TestMode=_u8(msg.test_mode),
        pointA=point(kit, msg.point_a_x, msg.point_a_y),
        pointB=point(kit, msg.point_b_x, msg.point_b_y),
        angleA=_i16(angle_a),
        angleB=_i16(angle_b),
        idA=_u8(msg.id_a),
        idB=_u8(msg.id_b),
        kickforce=_u8(msg.kick_force),
    )


def sending_off(kit: Kit, robot: Robot, team_index: int, off: bool) -> Any:
    """The referee's SendingOff: ``id_maxvel_isvalid`` = N sends robot N off, 10 + N brings it back."""
    return kit.make(
        "nubot_common/SendingOff",
        TeamName=robot.ros,
        TeamInfo=bool(team_index),
        PlayerNum=int(robot.rid),
        id_maxvel_isvalid=int(robot.rid) if off else 10 + int(robot.rid),
    )


def model_states(kit: Kit, msg: Any, names: Names) -> Any:
    """simatch's ModelStates (world frame, metres) as gazebo_msgs/ModelStates, models under their ROS names."""
    pose = np.asarray(msg.pose, dtype=float).reshape(-1, 7)
    twist = np.asarray(msg.twist, dtype=float).reshape(-1, 6)
    poses, twists = [], []
    for p, t in zip(pose, twist):
        poses.append(
            kit.make(
                "geometry_msgs/Pose",
                position=kit.make("geometry_msgs/Point", x=p[0], y=p[1], z=p[2]),
                orientation=kit.make("geometry_msgs/Quaternion", x=p[4], y=p[5], z=p[6], w=p[3]),
            )
        )
        twists.append(
            kit.make(
                "geometry_msgs/Twist",
                linear=kit.make("geometry_msgs/Vector3", x=t[0], y=t[1], z=t[2]),
                angular=kit.make("geometry_msgs/Vector3", x=t[3], y=t[4], z=t[5]),
            )
        )
    return kit.make("gazebo_msgs/ModelStates", name=[names.model_to_ros(n) for n in msg.name], pose=poses, twist=twists)


def clock(kit: Kit, stamp: float) -> Any:
    return kit.make("rosgraph_msgs/Clock", clock=kit.time(stamp))


def simulation_strategy(kit: Kit, infos: Iterable[Any]) -> Any:
    return kit.make("nubot_common/simulation_strategy", strategy_msgs=list(infos))


def velcmd_out(kit: Kit, msg: Any) -> Any:
    """simatch's VelCmd (m/s) as the original's (cm/s) — for recordings replayed into ROS."""
    return kit.make("nubot_common/VelCmd", Vx=float(msg.vx) * CM, Vy=float(msg.vy) * CM, w=float(msg.w))


def actioncmd_out(kit: Kit, msg: Any) -> Any:
    """simatch's ActionCmd as the original's: targets in cm, dribbler and kick (shootPos RUN 1 / FLY -1)."""
    move = NO_ACTION if msg.move_action == msgs.ActionCmd.NO_ACTION else 0
    rotate = NO_ACTION if msg.rotate_action == msgs.ActionCmd.NO_ACTION else 0
    mode = {msgs.ActionCmd.ROTATE_CCW: 1, msgs.ActionCmd.ROTATE_CW: -1}.get(int(msg.rotate_mode), 0)
    return kit.make(
        "nubot_common/ActionCmd",
        target=point(kit, msg.target_x, msg.target_y),
        target_ori=float(msg.target_ori),
        target_w=0.0,
        target_vel=point(kit, msg.target_vx, msg.target_vy),
        maxvel=float(msg.max_vel) * CM,
        maxw=float(msg.max_w),
        robot_pos=point(kit, 0.0, 0.0),
        robot_vel=point(kit, 0.0, 0.0),
        robot_ori=0.0,
        robot_w=0.0,
        move_action=move,
        rotate_acton=rotate,
        rotate_mode=mode,
        handle_enable=1 if msg.dribble else 0,
        strength=float(msg.kick_speed),
        shootPos=FLY if msg.kick_type == msgs.ActionCmd.KICK_LOB else RUN,
    )


def strategy_info_out(kit: Kit, msg: Any, seq: int = 0) -> Any:
    """simatch's StrategyInfo as the original's (pass points in cm)."""
    nums = [int(n) for n in np.asarray(msg.target_num).tolist()[:4]] + [0] * 4
    p = msg.pass_cmd
    return kit.make(
        "nubot_common/StrategyInfo",
        header=kit.header(seq, msg.stamp),
        AgentID=int(msg.agent_id),
        targetNum1=nums[0],
        targetNum2=nums[1],
        targetNum3=nums[2],
        targetNum4=nums[3],
        staticpassNum=int(msg.static_pass_num),
        staticcatchNum=int(msg.static_catch_num),
        role=int(msg.role),
        action=int(msg.action),
        is_dribble=bool(msg.is_dribble),
        is_kickoff=bool(msg.is_kickoff),
        role_time=float(msg.role_time),
        pass_cmd=kit.make(
            "nubot_common/PassCommands",
            pass_id=max(0, int(p.pass_id)),
            catch_id=max(0, int(p.catch_id)),
            pass_pt=point(kit, p.pass_x, p.pass_y),
            catch_pt=point(kit, p.catch_x, p.catch_y),
            is_passout=bool(p.is_passout),
            is_dynamic_pass=bool(p.is_dynamic_pass),
            is_static_pass=bool(p.is_static_pass),
            is_valid=bool(p.is_valid),
        ),
    )


# --- ROS -> simatch ------------------------------------------------------------------------------------------
_VelCmd = msgs.positional(msgs.VelCmd, "stamp tick vx vy w")


def velcmd_in(msg: Any, stamp: float, tick: int) -> Any:
    """The original's VelCmd (cm/s, body frame) as simatch's (m/s). Values pass unchecked (float32-rounded):
    the simulator refuses NaN and absurd ones and counts them, as for any process."""
    vx, vy, w = msgs.f32s(float(msg.Vx) / CM, float(msg.Vy) / CM, float(msg.w))
    return _VelCmd(float(stamp), int(tick), vx, vy, w)


def actioncmd_in(msg: Any, stamp: float, tick: int) -> Any:
    """The original's ActionCmd as simatch's: the dribbler (``handle_enable`` non-zero), the kick
    (``strength`` [m/s], non-zero fires; ``shootPos`` -1 lob, else ground), and the motion part (cm -> m)."""
    tx, ty, ori, tvx, tvy, max_vel, max_w, kick = msgs.f32s(
        float(msg.target.x) / CM,
        float(msg.target.y) / CM,
        float(msg.target_ori),
        float(msg.target_vel.x) / CM,
        float(msg.target_vel.y) / CM,
        float(msg.maxvel) / CM,
        float(msg.maxw),
        float(msg.strength),
    )
    mode = {1: msgs.ActionCmd.ROTATE_CCW, -1: msgs.ActionCmd.ROTATE_CW}.get(int(msg.rotate_mode), 0)
    return msgs.ActionCmd(
        stamp=float(stamp),
        tick=int(tick),
        move_action=msgs.ActionCmd.NO_ACTION if int(msg.move_action) == NO_ACTION else msgs.ActionCmd.MOVE,
        rotate_action=msgs.ActionCmd.NO_ACTION if int(msg.rotate_acton) == NO_ACTION else msgs.ActionCmd.MOVE,
        rotate_mode=mode,
        target_x=tx,
        target_y=ty,
        target_ori=ori,
        target_vx=tvx,
        target_vy=tvy,
        max_vel=max_vel,
        max_w=max_w,
        dribble=int(msg.handle_enable) != 0,
        kick_speed=kick,
        kick_type=msgs.ActionCmd.KICK_LOB if int(msg.shootPos) == FLY else msgs.ActionCmd.KICK_GROUND,
    )


def strategy_info_in(msg: Any, stamp: float, tick: int, rid: int) -> Any:
    """The original's StrategyInfo as simatch's (for the run's recording and viewers): roles and actions
    keep the NuBot numbering; ``rid`` is the robot whose topic it came on (its AgentID is not trusted)."""
    p = msg.pass_cmd
    px, py, cx, cy, role_time = msgs.f32s(
        float(p.pass_pt.x) / CM,
        float(p.pass_pt.y) / CM,
        float(p.catch_pt.x) / CM,
        float(p.catch_pt.y) / CM,
        float(msg.role_time),
    )
    return msgs.StrategyInfo(
        stamp=float(stamp),
        tick=int(tick),
        agent_id=int(rid),
        role=int(msg.role) & 0xFF,
        action=int(msg.action) & 0xFF,
        is_dribble=bool(msg.is_dribble),
        is_kickoff=bool(msg.is_kickoff),
        role_time=role_time,
        target_x=math.nan,
        target_y=math.nan,
        target_num=np.array([msg.targetNum1, msg.targetNum2, msg.targetNum3, msg.targetNum4], dtype=np.int32),
        static_pass_num=int(msg.staticpassNum),
        static_catch_num=int(msg.staticcatchNum),
        pass_cmd=msgs.PassCommands(
            pass_id=int(p.pass_id),
            catch_id=int(p.catch_id),
            pass_x=px,
            pass_y=py,
            catch_x=cx,
            catch_y=cy,
            is_passout=bool(p.is_passout),
            is_dynamic_pass=bool(p.is_dynamic_pass),
            is_static_pass=bool(p.is_static_pass),
            is_valid=bool(p.is_valid),
        ),
        user=np.zeros(0),
    )


class BadRequest(ValueError):
    """A ROS request that cannot be turned into a simatch one (one line: why)."""


def model_state_in(msg: Any, names: Names) -> Any:
    """gazebo_msgs/ModelState (world frame, metres) as simatch's ModelState request (names mapped back);
    BadRequest for an unknown model or a frame other than the world."""
    frame = str(msg.reference_frame)
    if frame not in ("", "world", "map"):
        raise BadRequest(f"set_model_state of {msg.model_name!r}: reference_frame {frame!r} (only the world)")
    name = names.model_from_ros(str(msg.model_name))
    if name is None:
        known = ", ".join([names.model_to_ros(n) for n in names.by_name] + ["football"])
        raise BadRequest(f"set_model_state: no model {msg.model_name!r} (models: {known})")
    p, o, lin, ang = msg.pose.position, msg.pose.orientation, msg.twist.linear, msg.twist.angular
    return msgs.ModelState(
        name=name,
        x=float(p.x),
        y=float(p.y),
        z=float(p.z),
        qw=float(o.w),
        qx=float(o.x),
        qy=float(o.y),
        qz=float(o.z),
        vx=float(lin.x),
        vy=float(lin.y),
        vz=float(lin.z),
        wx=float(ang.x),
        wy=float(ang.y),
        wz=float(ang.z),
    )


def fresh_strategies(latest: dict[int, tuple[float, Any]], now: float, stale_after: float, skip: Sequence[int]):
    """The original relay's choice: each robot's newest StrategyInfo received within ``stale_after``
    seconds, by id, the goalkeeper(s) in ``skip`` left out (it relayed robots 2..5 only)."""
    return [info for rid, (t, info) in sorted(latest.items()) if rid not in skip and now - t <= stale_after + 1e-9]
