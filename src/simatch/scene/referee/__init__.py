"""The automatic referee of RoboCup MSL matches (``judge.kind = "msl_referee"``); see docs/referee.md.

* `referee.MslReferee` — the judge node: state machine, restarts, commands, operator takeover;
* `rules/` — one rule per file; `state.py` — stages and phases; `log.py` — the append-only event log;
* `params.RefereeParams` — every threshold and time, under the scene's ``[judge]`` (MSL defaults).
"""

from .operator import OperatorError, OperatorRequest
from .params import RefereeParams
from .referee import MslReferee

__all__ = ["MslReferee", "OperatorError", "OperatorRequest", "RefereeParams"]
