"""The original's units, names and numbering, both ways (no ROS needed: rosbags' classes stand in)."""

from __future__ import annotations

import math
from types import SimpleNamespace as NS

import numpy as np
import pytest

import simatch
from simatch import msgs
from simatch.config.loader import SceneError, load_scene
from simatch.ros1 import convert
from simatch.ros1.bag import RosbagsKit, typestore
from simatch.ros1.names import Names

KIT = RosbagsKit(typestore())


def test_perception_is_in_centimetres_in_the_team_frame():
    with simatch.Simulation("msl_5v5", overrides={"judge.kind": "none"}) as sim:
        sim.set_model_state("ball", x=1.5, y=-2.0)
        got = {}
        for name in ("cyan/2", "magenta/2"):
            team, rid = name.split("/")
            sim.bus.subscribe(
                f"{team}/{rid}/OmniVisionInfo", msgs.OmniVisionInfo, lambda m, n=name: got.setdefault(n, m)
            )
        sim.step(1)
    cyan = convert.omnivision(KIT, got["cyan/2"], 7)
    assert (cyan.ballinfo.pos.x, cyan.ballinfo.pos.y) == pytest.approx((150.0, -200.0), abs=0.01)
    assert cyan.header.seq == 7 and cyan.ballinfo.ballinfostate == 1 and cyan.ballinfo.pos_known
    me = next(r for r in cyan.robotinfo if r.AgentID == 2)
    x0, y0, _ = (100.0 * v for v in load_scene("msl_5v5").spec.teams["cyan"].start[1])  # cyan/2's start pose, cm
    assert (me.pos.x, me.pos.y) == pytest.approx((x0, y0), abs=0.01)
    dist = math.hypot(150.0 - x0, -200.0 - y0)
    assert cyan.ballinfo.real_pos.radius == pytest.approx(dist, abs=0.01)
    assert len(cyan.obstacleinfo.pos) == 9 and len(cyan.robotinfo) == 5
    magenta = convert.omnivision(KIT, got["magenta/2"], 1)  # mirrored: magenta attacks +x in its frame too
    assert (magenta.ballinfo.pos.x, magenta.ballinfo.pos.y) == pytest.approx((-150.0, 200.0), abs=0.01)


def test_commands_come_in_as_si():
    vel = convert.velcmd_in(NS(Vx=150.0, Vy=-50.0, w=0.5), 1.25, 50)
    assert (vel.vx, vel.vy, vel.w, vel.stamp, vel.tick) == pytest.approx((1.5, -0.5, 0.5, 1.25, 50))
    bad = convert.velcmd_in(NS(Vx=math.nan, Vy=0.0, w=0.0), 0.0, 0)
    assert math.isnan(bad.vx)  # passed on: the simulator refuses it and counts it
    p = NS(x=0.0, y=0.0)
    action = NS(
        target=NS(x=300.0, y=-100.0),
        target_ori=1.0,
        target_vel=p,
        maxvel=250.0,
        maxw=3.0,
        move_action=16,
        rotate_acton=21,
        rotate_mode=-1,
        handle_enable=1,
        strength=6.5,
        shootPos=-1,
    )
    a = convert.actioncmd_in(action, 2.0, 80)
    assert a.dribble and a.kick_speed == pytest.approx(6.5) and a.kick_type == msgs.ActionCmd.KICK_LOB
    assert (a.target_x, a.target_y, a.max_vel) == pytest.approx((3.0, -1.0, 2.5))
    assert a.move_action == msgs.ActionCmd.MOVE and a.rotate_action == msgs.ActionCmd.NO_ACTION
    assert a.rotate_mode == msgs.ActionCmd.ROTATE_CW
    action.shootPos, action.handle_enable = 1, 0
    a = convert.actioncmd_in(action, 2.0, 80)
    assert a.kick_type == msgs.ActionCmd.KICK_GROUND and not a.dribble
    back = convert.actioncmd_out(KIT, a)
    assert back.handle_enable == 0 and back.shootPos == 1 and back.target.x == pytest.approx(300.0)


def test_game_commands_keep_the_original_numbering_and_limits():
    coach = msgs.new(msgs.CoachInfo, match_mode=15, match_type=1, max_vel=3.0, max_w=5.0)
    c = convert.coach_info(KIT, coach, 3, 12.5)
    assert (c.MatchMode, c.MatchType, c.angleA, c.angleB) == (15, 1, 300, 5)
    assert (c.header.stamp.sec, c.header.stamp.nanosec) == (12, 500_000_000)
    c = convert.coach_info(KIT, msgs.new(msgs.CoachInfo, match_mode=0), 4, 0.0)
    assert (c.angleA, c.angleB) == (450, 10)  # what the original's referee always sent


def test_names_and_the_world():
    spec = load_scene("msl_5v5").spec
    names = Names(spec)
    assert [r.ros for r in names.robots] == [f"NuBot{i}" for i in range(1, 6)] + [f"rival{i}" for i in range(1, 6)]
    assert names.team_topic("magenta", "receive_from_coach") == "/rival/receive_from_coach"
    assert names.model_from_ros("football") == "ball" and names.model_from_ros("rival3") == "magenta/3"
    other = Names(load_scene("msl_5v5", {"teams.cyan.ros_prefix": "Tech"}).spec)
    assert other.robots[0].ros == "Tech1"
    with pytest.raises(ValueError, match="same ROS prefix"):
        Names(load_scene("msl_5v5", {"teams.cyan.ros_prefix": "rival"}).spec)
    with pytest.raises(SceneError, match="ros_prefix"):
        load_scene("msl_5v5", {"teams.cyan.ros_prefix": "9 bad"})
    pose = NS(position=NS(x=1.0, y=2.0, z=0.11), orientation=NS(x=0.0, y=0.0, z=0.0, w=1.0))
    twist = NS(linear=NS(x=0.5, y=0.0, z=0.0), angular=NS(x=0.0, y=0.0, z=0.0))
    req = convert.model_state_in(NS(model_name="football", pose=pose, twist=twist, reference_frame=""), names)
    assert req.name == "ball" and (req.x, req.y, req.vx) == (1.0, 2.0, 0.5)
    with pytest.raises(convert.BadRequest, match="no model 'NuBot9'"):
        convert.model_state_in(NS(model_name="NuBot9", pose=pose, twist=twist, reference_frame=""), names)
    with pytest.raises(convert.BadRequest, match="reference_frame"):
        convert.model_state_in(NS(model_name="NuBot1", pose=pose, twist=twist, reference_frame="NuBot2"), names)
    states = msgs.new(
        msgs.ModelStates,
        name=["cyan/1", "ball"],
        pose=np.array([1, 2, 0, 1, 0, 0, 0, 3, 4, 0.11, 1, 0, 0, 0], dtype=np.float32),
        twist=np.zeros(12, dtype=np.float32),
    )
    out = convert.model_states(KIT, states, names)
    assert out.name == ["NuBot1", "football"] and out.pose[1].position.x == 3.0 and out.pose[0].orientation.w == 1.0
