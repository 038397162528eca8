"""In a real-time run the team bridge sends each cmd_vel on to the server as it arrives, not the newest one
at its next control tick: a client that publishes bursts of distinct speeds, several within one control
period, has (nearly) every one of them reach the server's process. Holding commands for the tick would let
about one per burst through. The server runs in this process, so that it can note every VelCmd it receives."""

from __future__ import annotations

import json

import pytest

from simatch import msgs
from simatch.bus import topics
from simatch.config.loader import load_scene
from simatch.distributed.server import Server

from .conftest import RosProcesses

pytestmark = pytest.mark.slow

BURSTS, SIZE = 15, 3  # three speeds at once, every 0.2 s (eight control periods)


def test_each_cmd_vel_reaches_the_server_as_it_arrives(rosprocs: RosProcesses, tmp_path):
    ps = rosprocs
    overrides = {"teams.cyan.strategy": "external", "teams.magenta.strategy": "none", "judge.kind": "none"}
    server = Server(
        load_scene("msl_5v5", overrides),
        listen=[ps.endpoint],
        run=ps.run,
        realtime=True,
        team_timeout=120,
        credentials_dir=str(ps.creds),
        say=lambda text: None,
    )
    arrived: list[float] = []
    # every VelCmd the simulator gets, sent alone or in a tick's bundle
    server.bus.subscribe(topics.robot_topic("cyan", 2, topics.VEL_CMD), msgs.VelCmd, lambda m: arrived.append(m.vx))
    bridge = None
    try:
        bridge = ps.bridge("--team", "cyan", key="cyan", name="team")
        client = ps.client("burst.py", "/cyan/robot2", str(BURSTS), str(SIZE), str(tmp_path / "sent.json"))
        server.wait_for_teams(timeout=120)
        while client.poll() is None:
            server.sim.run(seconds=0.5, until_done=False)
        server.sim.run(seconds=0.5, until_done=False)  # the last ones arrive
        assert client.returncode == 0, ps.stderr(client)
    finally:
        server.finish()
        if bridge is not None:
            ps.wait(bridge, 30)
        server.close()
    sent = {round(v, 3) for v in json.loads((tmp_path / "sent.json").read_text())}
    got = {round(v, 3) for v in arrived}
    assert len(sent) == BURSTS * SIZE
    assert len(sent & got) >= 0.8 * len(sent), f"{len(sent & got)} of {len(sent)} speeds reached the server"
