"""A judge with a manual action, as a referee would offer one to its operator: used by the tests to show
how such an action is made reproducible (published on the ``operator`` topic, listed in ``operator_calls``)."""

from __future__ import annotations

import json

from simatch import msgs
from simatch.bus import topics
from simatch.scene.judges import Judge


class ManualBallJudge(Judge):
    name = "manual_ball"
    operator_calls = ("drop_ball",)

    def start(self, ctx) -> None:
        super().start(ctx)
        self.pub_operator = ctx.bus.publisher(topics.OPERATOR, msgs.OperatorCommand)

    def drop_ball(self, x: float, y: float) -> None:
        """The operator drops the ball at (x, y)."""
        self.world.set_model_state("ball", x=x, y=y, z=0.11, vx=0.0, vy=0.0, vz=0.0)
        self.pub_operator.put(
            msgs.new(
                msgs.OperatorCommand,
                stamp=self.ctx.now(),
                step=self.ctx.step(),
                during_step=False,
                call="judge.drop_ball",
                args=json.dumps({"x": x, "y": y}),
            )
        )
