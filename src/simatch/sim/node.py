"""The simulator on the bus (the simulation interface).

`SimulatorNode` (phase SENSE) publishes, every physics step, the model/link states (float32) and ball
contacts, on every control tick the clock, the fingerprint of the exact states, the component fingerprints of
the steps since the last tick (`simatch.sim.components`) and each robot's
OmniVisionInfo (each only when somebody listens; a robot's perception may be taken at a later step of the
control period, its phase: see `set_vision_phase`); it takes every robot's VelCmd and ActionCmd.
`PhysicsNode` (phase ACT) applies the watchdog and advances the physics once every node has handled the
step. Both publish the world's inputs (`simatch.sim.inputs`) on ``world_inputs`` while somebody listens:
the SimulatorNode those made between two steps, the PhysicsNode those made while the step's nodes ran.
"""

from __future__ import annotations

import numpy as np

from .. import msgs
from ..bus import Node, NodeContext, Phase, topics
from .components import COMPONENTS, ComponentPrints
from .inputs import InputLog
from .simulator import Simulator, fingerprint  # noqa: F401 (fingerprint: for the reproduction)

# built positionally (every physics step; see msgs.positional)
_ModelStates = msgs.positional(msgs.ModelStates, "stamp step name pose twist")
_StateFingerprint = msgs.positional(msgs.StateFingerprint, "stamp step fingerprint")
_ComponentFingerprints = msgs.positional(msgs.ComponentFingerprints, "stamp step component fingerprint")
_Clock = msgs.positional(msgs.Clock, "stamp step tick")
_BallContacts = msgs.positional(msgs.BallContacts, "stamp step touching holder kicker kick_speed lob")
_F32 = np.float32  # the states' numbers, as the messages define them


def model_states_message(now: float, step: int, names, pose: np.ndarray, twist: np.ndarray):
    """The ModelStates message of the simulator's exact states (float32 numbers, as recorded)."""
    return _ModelStates(now, step, names, pose.astype(_F32).ravel(), twist.astype(_F32).ravel())


class SimulatorNode(Node):
    phase = Phase.SENSE
    name = "simulator"

    def __init__(self, sim: Simulator):
        self.sim = sim
        self.period = sim.dt
        self.control_steps = round(sim.scene.control.period / sim.dt)
        #: each robot's perception phase: the physics step of the control period at which it is taken
        #: (all 0, the control tick's first step, unless a real-time server spreads its processes out)
        self.vision_phase = [0] * len(sim.ix.robots)
        self._due: dict[int, list[int]] = {0: list(range(len(sim.ix.robots)))}
        self._due_at: list[list[int] | None] = self._due_table()

    def set_vision_phase(self, robot: int, phase: int) -> None:
        """Take robot ``robot``'s (index) perception at step ``phase`` of each control period from now on."""
        if not 0 <= phase < self.control_steps:
            raise ValueError(f"phase {phase} is not a step of a control period of {self.control_steps} steps")
        self.vision_phase[robot] = int(phase)
        due: dict[int, list[int]] = {}
        for i, p in enumerate(self.vision_phase):
            due.setdefault(p, []).append(i)
        self._due = due
        self._due_at = self._due_table()

    def _due_table(self) -> list[list[int] | None]:
        """The robots whose perception is due at each step of the control period (None: nobody's)."""
        return [self._due.get(into) for into in range(self.control_steps)]

    def start(self, ctx: NodeContext) -> None:
        super().start(ctx)
        bus, sim = ctx.bus, self.sim
        self.pub_clock = bus.publisher(topics.CLOCK, msgs.Clock)
        self.pub_models = bus.publisher(topics.MODEL_STATES, msgs.ModelStates)
        self.pub_fingerprint = bus.publisher(topics.STATE_FINGERPRINT, msgs.StateFingerprint)
        self.pub_components = bus.publisher(topics.COMPONENT_FINGERPRINTS, msgs.ComponentFingerprints)
        self.pub_links = bus.publisher(topics.LINK_STATES, msgs.LinkStates)
        self.pub_contacts = bus.publisher(topics.BALL_CONTACTS, msgs.BallContacts)
        self.pub_events = bus.publisher(topics.EVENTS, msgs.GameEvent)
        self.pub_inputs = bus.publisher(topics.WORLD_INPUTS, msgs.WorldInputs)
        self.pub_vision = []
        self.subs = []
        for i, entry in enumerate(sim.ix.robots):
            self.pub_vision.append(
                bus.publisher(topics.robot_topic(entry.team, entry.rid, topics.OMNI_VISION), msgs.OmniVisionInfo)
            )
            self.subs.append(
                bus.subscribe(
                    topics.robot_topic(entry.team, entry.rid, topics.VEL_CMD), msgs.VelCmd, self._vel_callback(i)
                )
            )
            self.subs.append(
                bus.subscribe(
                    topics.robot_topic(entry.team, entry.rid, topics.ACTION_CMD),
                    msgs.ActionCmd,
                    self._action_callback(i),
                )
            )

    # (the command methods are looked up at each call: while the world's inputs are logged, they are the
    # simulator's logging twins)
    def _vel_callback(self, i: int):
        sim = self.sim
        if i >= sim.ng:  # an aerial robot: with the upward speed

            def on_flight(msg) -> None:
                sim.command_velocity(i, msg.vx, msg.vy, msg.w, msg.vz)

            return on_flight

        def on_vel(msg) -> None:
            sim.command_velocity(i, msg.vx, msg.vy, msg.w)

        return on_vel

    def _action_callback(self, i: int):
        sim = self.sim
        lob = msgs.ActionCmd.KICK_LOB

        def on_action(msg) -> None:
            sim.command_action(i, msg.dribble, msg.kick_speed, msg.kick_type == lob)

        return on_action

    def tick(self, now: float) -> None:
        sim = self.sim
        k = sim.step_index
        inputs = sim._inputs  # the log itself, None while off
        if inputs is not None and inputs.kind:  # made between the steps: before this step's states go out
            if self.pub_inputs.active:
                self.pub_inputs.put(inputs.take(now, k, True))
            else:
                inputs.clear()
        if sim.perception.delay_steps:
            sim.perception.record(sim.snapshot())
        cs = self.control_steps
        into = k % cs
        if into == 0 and self.pub_clock.active:
            self.pub_clock.put(_Clock(now, k, k // cs))
        due = self._due_at[into]
        if due is not None:
            pubs = self.pub_vision
            for i in due:  # perception is made if anybody listens to one of the due robots
                if pubs[i].active:
                    infos = sim.observations(now, k // cs, None if len(due) == len(pubs) else due)
                    for j in due:
                        pub = pubs[j]
                        if pub.active:
                            pub.put(infos[j])
                    break
        if self.pub_models.active:
            self.pub_models.put(_ModelStates(now, k, sim.model_names, *sim.model_state_arrays32()))
        if into == 0:
            if self.pub_fingerprint.active:
                self.pub_fingerprint.put(_StateFingerprint(now, k, sim.state_fingerprint()))
            if sim.prints is not None or self.pub_components.active:
                self._component_prints(now)
        if self.pub_links.active:
            names, pose, twist = sim.link_state_arrays()
            self.pub_links.put(
                msgs.LinkStates(
                    stamp=now, step=k, name=names, pose=pose.astype(_F32).ravel(), twist=twist.astype(_F32).ravel()
                )
            )
        if self.pub_contacts.active:
            touching = sim.ball_touches()
            ball = sim.ball
            holder, kicker = ball.holder, ball.kicked_by
            if touching or holder >= 0 or kicker >= 0:
                names = sim.robot_names
                self.pub_contacts.put(
                    _BallContacts(
                        now,
                        k,
                        list(map(names.__getitem__, touching)),
                        names[holder] if holder >= 0 else "",
                        names[kicker] if kicker >= 0 else "",
                        ball.kicked_speed if kicker >= 0 else 0.0,
                        bool(ball.kicked_lob) if kicker >= 0 else False,
                    )
                )
        if sim.events:
            self.flush_events()

    def _component_prints(self, now: float) -> None:
        """At a control tick: the component fingerprints of the steps since the last one go out, and they are
        taken from now on while somebody listens (`simatch.sim.components`), not at all while nobody does."""
        sim = self.sim
        if not self.pub_components.active:
            sim.prints = None
            return
        if sim.prints is None:
            sim.prints = ComponentPrints(sim)
            return
        first, rows = sim.prints.take()
        if len(rows):
            self.pub_components.put(_ComponentFingerprints(now, first, list(COMPONENTS), rows))

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
        self._log = sim.inputs

    def start(self, ctx: NodeContext) -> None:
        super().start(ctx)
        self.pub_inputs = ctx.bus.publisher(topics.WORLD_INPUTS, msgs.WorldInputs)

    def tick(self, now: float) -> None:
        sim = self.sim
        inputs = sim._inputs  # the log itself, None while off
        listened = self.pub_inputs.active
        if inputs is not None and inputs.kind:
            if listened:
                self.pub_inputs.put(inputs.take(now, sim.step_index, False))
            else:
                inputs.clear()
        sim.advance()
        if sim.events:
            self.sensor.flush_events()
        # the inputs are logged while somebody listens (from the start on: a recorder attached before the
        # first step has everything)
        if listened:
            if inputs is None:
                sim.inputs = inputs = self._log or InputLog()
                self._log = inputs
        elif inputs is not None:
            self._log, sim.inputs = inputs, None
