"""Sensing: what the robots perceive of the world, and which robots touch the ball.

Every control tick each robot gets its OmniVisionInfo (`simatch.sim.perception`), made from the world as it
is now (or as it was, with a latency). Where perception is exact and every robot is on the ground (the
shipped matches), one compiled call reads the engine's arrays straight into the messages' numbers
(`kernels.sense_ground`); otherwise a `Snapshot` of the world is taken and observed with noise, dropouts,
sight rules and heights. Both compute the numbers with the same kernels (`kernels.robot_flags`,
`kernels.perceive`), so the messages are the same bit for bit.

The ball's contacts with robots are read from the engine's contact list, after a compiled test that most
steps answers that no robot is near enough for a contact at all.

`Sensing` is a part of `simatch.sim.simulator.Simulator` (its methods are the simulator's).
"""

from __future__ import annotations

import mujoco
import numpy as np

from ..compiled import bind
from .kernels import FlagInputs, Joints, ball_apart, robot_flags, sense_ground
from .perception import Perception, Snapshot
from .sight import Sight

_F32 = np.float32


class Sensing:
    """The simulator's sensing methods (see the module)."""

    def _init_sensing(self, seed: int) -> None:
        scene, e, ng = self.scene, self.engine, self.ng
        self.perception = Perception(
            self.ix.robots,
            self.signs,
            self.radii,
            np.concatenate((self.drive.n_wheels, np.zeros(self.n - ng, dtype=int))),
            scene.perception,
            self.dt,
            np.random.default_rng([seed & 0xFFFFFFFF, 0x5E45E]),
            sight=Sight.of(self.robot_models, self.field, scene.perception),
        )
        self.stuck = np.zeros(self.n, dtype=bool)
        self._slow_since = np.full(self.n, -1, dtype=np.int64)
        F = self.field
        self._flag_inputs = FlagInputs(
            e.setpoint,
            self.drive.M,
            self.drive.n_wheels.astype(np.int64),
            self.enabled,
            self._slow_since,
            round(0.5 / self.dt),  # stuck after half a second
            float(F.half_length),
            float(F.half_width),
        )
        self._joints = Joints(e.robot_q, e.robot_v, e.ball_q, e.ball_v)
        p = self.perception
        #: `observations` by one compiled call: exact perception of ground robots alone
        self._sense_fast = self.aerial is None and p.exact and p.sight is None and p.delay_steps == 0 and self.n > 0
        self._sense = bind(sense_ground)
        self._robot_flags = bind(robot_flags)
        self._init_touch_bounds()

    def observations(self, stamp: float, tick: int, only: list[int] | None = None) -> list:
        """Every robot's OmniVisionInfo now (``only``: those robots', None in the others' places), as
        `Perception.observe` makes them from a `snapshot` (which updates the robots' 'stuck' flags) delayed by
        the perception's latency; for exact perception of ground robots, straight from the engine's arrays
        (`kernels.sense_ground`) into the same messages."""
        p = self.perception
        if only is not None or not self._sense_fast:
            return p.observe(p.delayed(self.snapshot()), stamp, tick, only)
        e, n = self.engine, self.n
        obs = np.empty((6 * n, n - 1), dtype=_F32)  # fresh: the messages keep its rows
        wheels = np.empty((n, self.drive.max_wheels), dtype=_F32)
        self._sense(
            e.qpos,
            e.qvel,
            self._joints,
            self._flag_inputs,
            self.step_index,
            p.sign,
            p.others,
            p.noise_free,
            p.R,
            p.ball,
            p.own32,
            p.balls32,
            obs,
            wheels,
            p.valid,
            p.stuck,
        )
        self.stuck = p.stuck
        return p.observe_exact(obs, wheels, self.ball.holder, stamp, tick)

    def snapshot(self) -> Snapshot:
        """The current world for perception (also updates each robot's 'stuck' flag)."""
        flying = self.aerial_arrays() if self.aerial is not None else None
        R = self.robot_array(flying)
        wheels = np.empty((self.n, self.drive.max_wheels))
        valid = np.empty(self.n, dtype=bool)
        stuck = np.empty(self.n, dtype=bool)
        self._robot_flags(R, self._flag_inputs, self.step_index, wheels, valid, stuck)
        heights = self.robot_heights(flying) if self.aerial is not None else None
        self.stuck = stuck
        return Snapshot(
            step=self.step_index,
            robots=R,
            ball=self.ball_array(),
            holder=self.ball.holder,
            wheels=wheels,
            valid=valid,
            stuck=stuck.copy(),
            heights=heights,
        )

    # --- the ball's contacts with robots ---------------------------------------------------------------------
    def _init_touch_bounds(self) -> None:
        """The robots' geoms and, for each, how far its centre must be from the ball's for the engine to
        make no contact between them (see `kernels.ball_apart`): both bounding spheres, the largest margin
        a contact may have (geoms', explicit pairs', the global override), and a centimetre to spare. A geom
        without a bounding sphere (a plane) never counts as apart."""
        m = self.m
        self._geom_robot = np.full(m.ngeom, -1, dtype=np.int64)
        for g, i in self.ix.robot_of_geom.items():
            self._geom_robot[g] = i
        self._geom_robot_list = self._geom_robot.tolist()
        geoms = np.flatnonzero(self._geom_robot >= 0)
        margin = max(float(m.geom_margin.max(initial=0.0)), float(m.pair_margin.max(initial=0.0)))
        if m.opt.enableflags & mujoco.mjtEnableBit.mjENBL_OVERRIDE:
            margin = max(margin, float(m.opt.o_margin))
        rball = float(m.geom_rbound[self.ix.ball_geom])
        rb = m.geom_rbound[geoms]
        bound = np.where((rb > 0) & (rball > 0), rb + rball + margin + 0.01, np.inf)
        self._touch_geoms, self._touch_bound2 = geoms.astype(np.int64), bound * bound
        self._ball_geom = int(self.ix.ball_geom)
        self._ball_apart = bind(ball_apart)

    def ball_touches(self) -> list[int]:
        """Robots whose mouth touches the ball right now (from the engine's contacts).

        Most steps no robot is near enough to the ball for a contact, which the compiled test of the bounding
        spheres tells without reading the engine's contact list; a held ball is in its holder's mouth and
        skips the test. The few contacts are then scanned as plain ints."""
        bg = self._ball_geom
        if self.ball.holder < 0 and self._ball_apart(self.engine.geom_xpos, self._touch_geoms, self._touch_bound2, bg):
            return []
        d = self.d
        n = d.ncon
        if n == 0:
            return []
        flat = d.contact.geom.ravel().tolist()  # the engine's ncon contacts: its rows are those alone
        if bg not in flat:
            return []
        robot_of = self._geom_robot_list
        robots = set()
        for k in range(0, 2 * n, 2):
            a, b = flat[k], flat[k + 1]
            r = robot_of[b] if a == bg else robot_of[a] if b == bg else -1
            if r >= 0:
                robots.add(r)
        return sorted(robots)
