"""`BridgeProcess`: ``simatch ros1 TEAM --connect ...``, a team process of a distributed run whose robots
are played by ROS nodes.

It is `TeamProcess` (the same join, credentials, lockstep ticks, watchdog and goodbye) with the bridge in
place of the team's strategy nodes: the server sees a team process like any other, and fair play holds
through it (a team's credential commands that team only and never the world; with the organiser's
``admin`` credential the bridge also carries ``/gazebo/model_states`` and ``/gazebo/set_model_state``).
"""

from __future__ import annotations

from ..distributed import credentials, protocol
from ..distributed.client import TeamProcess
from .bridge import Options, RosBridge


class BridgeProcess(TeamProcess):
    runs_strategy = False  # ROS nodes drive its robots

    def __init__(
        self,
        team: str,
        *,
        answer_timeout: float = 1.0,
        wait_ros: float = 30.0,
        clock: bool = True,
        strategy_relay: bool = True,
        **kwargs,
    ):
        super().__init__(team, None, **kwargs)
        self.answer_timeout = answer_timeout
        self.wait_ros = wait_ros
        self.publish_clock = clock
        self.strategy_relay = strategy_relay
        self.bridge: RosBridge | None = None
        self.credential_name = ""

    def _credential(self) -> credentials.Credential:
        cred = super()._credential()
        self.credential_name = cred.name
        return cred

    def nodes(self) -> list:
        spec = self.scene.spec
        options = Options(
            teams=[self.team],
            watch=[self.team],
            world=self.credential_name == credentials.ADMIN,
            lockstep=self.mode == protocol.LOCKSTEP,
            answer_timeout=self.answer_timeout,
            clock=self.publish_clock,
            strategy_relay=self.strategy_relay,
            node_name=f"simatch_bridge_{self.team}",
        )
        bridge = self.bridge = RosBridge(spec, options, phase_step=self.phase, say=self.say)
        bridge.connect_ros()
        if self.mode == protocol.REALTIME:
            bridge.forward_now = self._forward
        missing = bridge.wait_for_ros(self.wait_ros)
        if missing:
            self.say(f"no ROS nodes for {', '.join(missing)} after {self.wait_ros:g} s: joining without them")
        else:
            self.say(f"ROS nodes of {self.team} attached")
        return [bridge]

    def _forward(self) -> None:
        """Real time: what ROS just sent leaves at once (between two ticks, never inside one's bundle)."""
        with self._delivering:
            bridge, bus = self.bridge, self.bus
            if bridge is not None and bus is not None and self.joined and not self.ended:
                bridge.hand_over()
