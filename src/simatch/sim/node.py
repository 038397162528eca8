"""The simulator on the bus (the simulation interface).

`SimulatorNode` (phase SENSE) publishes, every physics step, the clock, the model/link states (float32,
with a fingerprint of the exact ones) and ball contacts (each only when somebody listens), and on every
control tick each robot's OmniVisionInfo; it takes every robot's VelCmd and ActionCmd. `PhysicsNode` (phase ACT) applies the
watchdog and advances the physics once every node has handled the step.
"""

from __future__ import annotations

import hashlib

import numpy as np

from .. import msgs
from ..bus import Node, NodeContext, Phase, topics
from .simulator import Simulator

# built positionally (every physics step; see msgs.positional)
_ModelStates = msgs.positional(msgs.ModelStates, "stamp step name pose twist fingerprint")
_F32 = np.float32             # the states' numbers, as the messages define them
_blake2b = hashlib.blake2b
_from_bytes = int.from_bytes


def fingerprint(pose: np.ndarray, twist: np.ndarray) -> int:
    """The ModelStates/LinkStates fingerprint of the exact (float64, C-ordered) poses and twists: equal
    fingerprints mean the same states bit for bit (a 64-bit hash; a chance difference is 1 in 1.8e19)."""
    h = _blake2b(np.ascontiguousarray(pose, dtype=np.float64), digest_size=8)
    h.update(np.ascontiguousarray(twist, dtype=np.float64))
    return _from_bytes(h.digest(), "little")


_Clock = msgs.positional(msgs.Clock, "stamp step tick")


class SimulatorNode(Node):
    phase = Phase.SENSE
    name = "simulator"

    def __init__(self, sim: Simulator):
        self.sim = sim
        self.period = sim.dt
        self.control_steps = round(sim.scene.control.period / sim.dt)

    def start(self, ctx: NodeContext) -> None:
        super().start(ctx)
        bus, sim = ctx.bus, self.sim
        self.pub_clock = bus.publisher(topics.CLOCK, msgs.Clock)
        self.pub_models = bus.publisher(topics.MODEL_STATES, msgs.ModelStates)
        self.pub_links = bus.publisher(topics.LINK_STATES, msgs.LinkStates)
        self.pub_contacts = bus.publisher(topics.BALL_CONTACTS, msgs.BallContacts)
        self.pub_events = bus.publisher(topics.EVENTS, msgs.GameEvent)
        self.pub_vision = []
        self.subs = []
        for i, entry in enumerate(sim.ix.robots):
            self.pub_vision.append(bus.publisher(topics.robot_topic(entry.team, entry.rid, topics.OMNI_VISION),
                                                 msgs.OmniVisionInfo))
            self.subs.append(bus.subscribe(topics.robot_topic(entry.team, entry.rid, topics.VEL_CMD), msgs.VelCmd,
                                           self._vel_callback(i)))
            self.subs.append(bus.subscribe(topics.robot_topic(entry.team, entry.rid, topics.ACTION_CMD),
                                           msgs.ActionCmd, self._action_callback(i)))

    def _vel_callback(self, i: int):
        command = self.sim.command_velocity

        def on_vel(msg) -> None:
            command(i, msg.vx, msg.vy, msg.w)
        return on_vel

    def _action_callback(self, i: int):
        command = self.sim.command_action
        lob = msgs.ActionCmd.KICK_LOB

        def on_action(msg) -> None:
            command(i, msg.dribble, msg.kick_speed, msg.kick_type == lob)
        return on_action

    def tick(self, now: float) -> None:
        sim = self.sim
        k = sim.step_index
        perception = sim.perception
        if perception.delay_steps:
            perception.record(sim.snapshot())
        if k % self.control_steps == 0:
            tick = k // self.control_steps
            if self.pub_clock.active:
                self.pub_clock.put(_Clock(now, k, tick))
            if any(p.active for p in self.pub_vision):
                snap = sim.snapshot()
                for pub, info in zip(self.pub_vision, perception.observe(perception.delayed(snap), now, tick)):
                    if pub.active:
                        pub.put(info)
        if self.pub_models.active:
            names, pose, twist = sim.model_state_arrays()
            self.pub_models.put(_ModelStates(now, k, names, pose.astype(_F32).ravel(), twist.astype(_F32).ravel(),
                                              fingerprint(pose, twist)))
        if self.pub_links.active:
            names, pose, twist = sim.link_state_arrays()
            self.pub_links.put(msgs.LinkStates(stamp=now, step=k, name=names, pose=pose.astype(_F32).ravel(),
                                               twist=twist.astype(_F32).ravel(), fingerprint=fingerprint(pose, twist)))
        if self.pub_contacts.active:
            touching = sim.ball_touches()
            holder, kicker = sim.ball.holder, sim.ball.kicked_by
            if touching or holder >= 0 or kicker >= 0:
                names = sim.robot_names
                self.pub_contacts.put(msgs.BallContacts(
                    stamp=now, step=k, touching=[names[i] for i in touching],
                    holder=names[holder] if holder >= 0 else "", kicker=names[kicker] if kicker >= 0 else "",
                    kick_speed=sim.ball.kicked_speed if kicker >= 0 else 0.0,
                    lob=bool(sim.ball.kicked_lob) if kicker >= 0 else False))
        if sim.events:
            self.flush_events()

    def flush_events(self) -> None:
        for ev in self.sim.take_events():
            self.pub_events.put(ev)

    def stop(self) -> None:
        for sub in self.subs:
            sub.close()
        self.subs.clear()


class PhysicsNode(Node):
    """Advances the world by one physics step after every other node has handled the current one."""

    phase = Phase.ACT
    name = "physics"

    def __init__(self, sim: Simulator, sensor: SimulatorNode):
        self.sim = sim
        self.sensor = sensor
        self.period = sim.dt
        self.control_steps = sensor.control_steps
        self.timeout = sim.scene.control.command_timeout

    def tick(self, now: float) -> None:
        sim = self.sim
        if sim.step_index % self.control_steps == 0:
            sim.watchdog(self.timeout, self.control_steps)
        sim.step()
        if sim.events:
            self.sensor.flush_events()
