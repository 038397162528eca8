"""nubot: the default team of simatch, playing RoboCup MSL soccer by the rules.

Named ``"nubot"`` in a scene (``teams.<team>.strategy = "nubot"``); tunables in
``teams.<team>.strategy_params`` (see `NubotParams`). The design follows NuBot's role architecture
(simatch-original.md section 6): dynamic roles by utility with hysteresis (picture.py), interception on
the predicted ball path (ballpath.py), sub-target obstacle avoidance (avoidance.py), the active robot's
shoot / pass / dribble choices within the 3 m rule (active.py), a goalkeeper that fits the ball's flight
(goalie.py), set-piece positions for every game command (setpieces.py, restart.py), parking and the
coach's test commands (testmodes.py).
"""

from .params import NubotParams
from .robot import NubotRobot, NubotTeam

__all__ = ["NubotParams", "NubotRobot", "NubotTeam"]
