"""Fair play: a process holding a team's credential commands only that team's robots, cannot call the
Gazebo-like interface, cannot read the other team's perception or the ground truth; what it may not send is
refused and logged, a malformed payload is dropped and counted; the organiser's credential may do everything.
A real server, a real team process and, in this test process, two more clients over real Zenoh."""

from __future__ import annotations

import math
import time

import pytest

from simatch import msgs
from simatch.bus import bundle
from simatch.bus.zenoh_bus import TransportError, ZenohBus, open_session, zenoh_config
from simatch.distributed import credentials

from .cluster import chaser_overrides


def connect(procs, name: str, secret: str | None = None, wait: float = 5.0) -> ZenohBus:
    cred = credentials.read(procs.creds / f"{name}.key")
    conf = zenoh_config("client", connect=[procs.endpoint], user=cred.name, password=secret or cred.secret)
    return ZenohBus(open_session(conf, wait=wait), procs.run, signer=cred.signer(procs.run), eager=True)


def wait_for(path, timeout=60.0):
    deadline = time.monotonic() + timeout
    while not path.exists():
        assert time.monotonic() < deadline, f"{path} never appeared"
        time.sleep(0.1)


@pytest.mark.slow
def test_teams_are_confined_to_their_own_robots(procs):
    server = procs.server(
        "msl_5v5", *chaser_overrides("cyan"), "--set", "teams.magenta.strategy=none", "--realtime", "--duration", "6"
    )
    team = procs.team("cyan")
    wait_for(procs.creds / "admin.key")
    time.sleep(0.5)  # the server writes the users file, then opens its router
    rogue = connect(procs, "cyan")  # holds cyan's credential, and misbehaves
    admin = connect(procs, "admin")  # the organiser's tools
    try:
        with pytest.raises(TransportError):
            connect(procs, "magenta", secret="00" * 32, wait=0)  # a wrong password cannot even connect
        states, spied, mine = [], [], []
        admin.subscribe("model_states", msgs.ModelStates, states.append)
        rogue.subscribe("magenta/*/OmniVisionInfo", msgs.OmniVisionInfo, spied.append)
        rogue.subscribe("model_states", msgs.ModelStates, spied.append)
        rogue.subscribe("cyan/2/OmniVisionInfo", msgs.OmniVisionInfo, mine.append)
        deadline = time.monotonic() + 60
        while not states:  # the match is on
            assert time.monotonic() < deadline
            admin.pump(0.1)
        steal = rogue.publisher("magenta/2/VelCmd", msgs.VelCmd)
        cheat = rogue.publisher("set_model_state", msgs.ModelState)
        push = rogue.publisher("apply_wrench", msgs.ApplyWrench)
        own = rogue.key("cyan/2/VelCmd")
        organise = admin.publisher("set_model_state", msgs.ModelState)
        relink = admin.publisher("set_link_state", msgs.LinkState)
        shove = admin.publisher("apply_wrench", msgs.ApplyWrench)
        poison = admin.key("lockstep/feed/cyan/0")  # the team hears its perception only from its feed
        ovi = msgs.msgtype_name(msgs.OmniVisionInfo)
        poisoned = bundle.pack([("cyan/2/OmniVisionInfo", ovi, b"junk")])
        mine_bundle = rogue.key("cyan/lockstep/bundle")
        vel = msgs.msgtype_name(msgs.VelCmd)
        smuggled = bundle.pack(
            [
                ("cyan/2/VelCmd", vel, msgs.encode(msgs.new(msgs.VelCmd))),
                ("magenta/3/VelCmd", vel, msgs.encode(msgs.new(msgs.VelCmd, vx=2.0))),
            ]
        )
        for k in range(20):
            steal.put(msgs.new(msgs.VelCmd, vx=2.0))
            cheat.put(msgs.new(msgs.ModelState, name="ball", x=10.0, y=0.0, z=0.11))
            push.put(msgs.new(msgs.ApplyWrench, name="magenta/3", fx=500.0, duration=0.5))
            rogue.session.put(rogue.key("magenta/4/VelCmd"), msgs.encode(msgs.new(msgs.VelCmd, vx=2.0)))  # unsigned
            data = b"\x00\x01\x00\x00not a VelCmd"
            rogue.session.put(own, data, attachment=rogue.signer("cyan/2/VelCmd", data))  # signed, malformed
            admin.session.put(poison, poisoned, attachment=admin.signer("lockstep/feed/cyan/0", poisoned))
            admin.session.put(poison, b"junk", attachment=admin.signer("lockstep/feed/cyan/0", b"junk"))
            # a bundle may carry only what its sender may send alone; its signature covers every entry
            rogue.session.put(mine_bundle, smuggled, attachment=rogue.signer("cyan/lockstep/bundle", smuggled))
            rogue.session.put(mine_bundle, smuggled, attachment=rogue.signer("cyan/lockstep/bundle", b"other"))
            rogue.session.put(mine_bundle, b"SMB1\xff", attachment=rogue.signer("cyan/lockstep/bundle", b"SMB1\xff"))
            if k == 5:
                organise.put(msgs.new(msgs.ModelState, name="magenta/5", x=6.0, y=-4.0))
                relink.put(msgs.new(msgs.LinkState, name="magenta/1/base", x=9.0, y=1.0))
                shove.put(msgs.new(msgs.ApplyWrench, name="nobody", fx=1.0, duration=0.1))  # refused by the world
            admin.pump(0.02)
            rogue.pump(0.02)
        out = procs.result(server)
        admin.pump(0.2)
        rogue.pump(0.2)
    finally:
        rogue.close()
        admin.close()
    assert procs.wait(team) == 0
    refused = [e for e in out["events"] if e["type"] == "refused"]
    details = " | ".join(e["detail"] for e in refused)
    assert "cyan may not command magenta/2 (VelCmd)" in details
    assert "cyan may not command magenta/3 (VelCmd)" in details  # smuggled in a bundle
    assert "unsigned or forged sample on cyan/lockstep/bundle" in details
    assert any(e["type"] == "malformed_message" and "cyan/lockstep/bundle" in e["detail"] for e in out["events"])
    assert "cyan may not call set_model_state" in details and "cyan may not call apply_wrench" in details
    assert "unsigned or forged sample on magenta/4/VelCmd" in details
    assert all(e["team"] == "cyan" for e in refused if "unsigned" not in e["detail"])
    assert any(e["type"] == "malformed_message" and "cyan/2/VelCmd" in e["detail"] for e in out["events"])
    stderr = procs.stderr(team)  # the team process dropped the junk, and lived
    assert (
        "malformed sample on cyan/2/OmniVisionInfo" in stderr and "malformed sample on lockstep/feed/cyan/0" in stderr
    )

    names = list(states[-1].name)
    pose = states[-1].pose.reshape(len(names), -1)
    for s in states:  # magenta/2, 3, 4 never moved
        p = s.pose.reshape(len(names), -1)
        for robot, start in (("magenta/2", (3.5, -1.0)), ("magenta/3", (3.5, 1.0)), ("magenta/4", (5.0, -2.0))):
            i = names.index(robot)
            assert math.hypot(p[i, 0] - start[0], p[i, 1] - start[1]) < 1e-6, robot
    ball = names.index("ball")
    assert all(abs(s.pose.reshape(len(names), -1)[ball, 0] - 10.0) > 1.0 for s in states)
    i5, i1 = names.index("magenta/5"), names.index("magenta/1")
    assert pose[i5, 0] == pytest.approx(6.0, abs=1e-6) and pose[i5, 1] == pytest.approx(-4.0, abs=1e-6)
    assert pose[i1, 0] == pytest.approx(9.0, abs=1e-6) and pose[i1, 1] == pytest.approx(1.0, abs=1e-6)
    bad = [e for e in out["events"] if e["type"] == "bad_request"]
    assert len(bad) == 1 and "apply_wrench('nobody')" in bad[0]["detail"]
    assert spied == [] and mine  # its own perception only
