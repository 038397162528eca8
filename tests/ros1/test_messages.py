"""The message packages are the original's interface: ROS's own tools give our .msg files the md5sums of
the original Simatch's, so that nodes built against the original nubot_common talk to the bridge."""

from __future__ import annotations

import subprocess

from simatch.ros1 import rosenv

# md5sums of the original Simatch's message files (nubot-nudt/simatch, master, src/robot_code/nubot_common/
# msgs/, the v2 interface; gazebo_msgs: the standard gazebo_ros package), computed by genmsg from those
# files. Three are also published elsewhere and agree: VelCmd 914217797e9c6227... and CoachInfo
# 7bb01a0f4328cb28... (simatch's reference digest), simulation_strategy 1d84999556ec502f... (code generated
# from the original nubot_common).
ORIGINAL_MD5 = {
    "nubot_common/ActionCmd": "e204a5c5aa57094f9f1d312ee6cf39ca",
    "nubot_common/Angle": "7328b114b91e2487fcf12e1581a80145",
    "nubot_common/BallInfo": "06211c2a8d639c68390f487a28e6a33a",
    "nubot_common/BallIsHolding": "54632c03708fe2af90615888ddba8d4e",
    "nubot_common/CoachInfo": "7bb01a0f4328cb28beb61d4f502c2969",
    "nubot_common/ObstaclesInfo": "8850a2241dd98578d2d66d842f5946c8",
    "nubot_common/OminiVisionInfo": "71f66ce5416c122d9955b156151ea395",
    "nubot_common/PPoint": "29d7d0dfcbdb558f82b1c2caff948161",
    "nubot_common/PassCommands": "d50d66ad0a96e8d9eae8a7a9da579ad2",
    "nubot_common/Point2d": "ff8d7d66dd3e4b731ef14a45d38888b6",
    "nubot_common/RobotInfo": "b4ae67161bf4b86c0bc4c4f720e02189",
    "nubot_common/SendingOff": "9191751af64414be11d66149d6cb5102",
    "nubot_common/StrategyInfo": "9983cea3e357670f055f12d4322a06c9",
    "nubot_common/VelCmd": "914217797e9c6227112d1ec2a4b462eb",
    "nubot_common/WorldModelInfo": "7d184d155b8f964299d2ae834875aebd",
    "nubot_common/simulation_strategy": "1d84999556ec502fdeaed67902dd635f",
    "gazebo_msgs/ModelState": "9330fd35f2fcd82d457e54bd54e10593",
    "gazebo_msgs/ModelStates": "48c080191eb15c41858319b4d8a609c2",
}


def test_rosmsg_gives_the_original_md5sums():
    env = rosenv.environment()
    for msgtype in ("nubot_common/VelCmd", "nubot_common/CoachInfo", "nubot_common/OminiVisionInfo"):
        out = subprocess.run(["rosmsg", "md5", msgtype], capture_output=True, text=True, env=env, timeout=60)
        assert out.returncode == 0, out.stderr
        assert out.stdout.strip() == ORIGINAL_MD5[msgtype], msgtype
    shown = subprocess.run(
        ["rosmsg", "show", "nubot_common/ActionCmd"], capture_output=True, text=True, env=env, timeout=60
    )
    assert "int64 handle_enable" in shown.stdout and "int64 shootPos" in shown.stdout, shown.stderr


def test_every_shipped_message_has_the_original_md5sum():
    """genmsg (what rosmsg and catkin use) on every shipped .msg file, and genpy's generated classes."""
    ws = rosenv.workspace()
    script = (
        "import sys, genmsg, genmsg.msg_loader as ml, genmsg.gentools as gt\n"
        "ctx = genmsg.MsgContext.create_default()\n"
        f"share = {str(ws / 'share')!r}\n"
        "search = {'std_msgs': ['/usr/share/std_msgs/msg'], 'geometry_msgs': ['/usr/share/geometry_msgs/msg'],\n"
        "          'nubot_common': [share + '/nubot_common/msg'], 'gazebo_msgs': [share + '/gazebo_msgs/msg']}\n"
        "import nubot_common.msg, gazebo_msgs.msg\n"
        "for t in sys.argv[1:]:\n"
        "    spec = ml.load_msg_by_type(ctx, t, search); ml.load_depends(ctx, spec, search)\n"
        "    pkg, name = t.split('/')\n"
        "    cls = getattr(sys.modules[pkg + '.msg'], name)\n"
        "    print(t, gt.compute_md5(ctx, spec), cls._md5sum)\n"
    )
    out = subprocess.run(
        [str(rosenv.SYSTEM_PYTHON), "-c", script, *ORIGINAL_MD5],
        capture_output=True,
        text=True,
        env=rosenv.environment(),
        timeout=60,
    )
    assert out.returncode == 0, out.stderr
    got = {}
    for line in out.stdout.split("\n"):
        if line:
            t, md5, generated = line.split()
            assert md5 == generated, t
            got[t] = md5
    assert got == ORIGINAL_MD5
    shipped = {f"{p}/{f.stem}" for p in rosenv.MESSAGE_PACKAGES for f in (rosenv.SHARE / p / "msg").glob("*.msg")}
    assert shipped == set(ORIGINAL_MD5)


def test_the_bag_writer_gives_the_same_md5sums():
    from simatch.ros1.bag import typestore

    store = typestore()
    for msgtype, md5 in ORIGINAL_MD5.items():
        pkg, name = msgtype.split("/")
        assert store.generate_msgdef(f"{pkg}/msg/{name}")[1] == md5, msgtype
