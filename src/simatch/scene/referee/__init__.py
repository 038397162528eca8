"""The automatic referee of RoboCup MSL matches (``judge.kind = "msl_referee"``); see docs/referee.md.

One concern per file, as the rules are one rule per file:

* `referee.MslReferee` — the judge node: the state machine (phases, transitions) and its decisions;
* `state.py` — the stages and phases and the transitions allowed; `stages.py` — going from stage to stage
  (halves, change of ends, end of the match); `shootout.py` — the penalty shoot-out;
* `rules/` — one rule per file, each returning `Call`s; `match.py` — what the rules read;
* `observation.py`, `touches.py`, `contacts.py` — what the referee sees: states, ball touches, robot contacts;
* `restarts.py` — restarts and their spots; `discipline.py` — cards and sending off;
* `log.py` — the append-only event log; `report.py` — the game, the result, the GameState message;
* `takeover.py`, `operator.py` — the operator's requests and their checks;
* `params.RefereeParams` — every threshold and time, under the scene's ``[judge]`` (MSL defaults).
"""

from .operator import OperatorError, OperatorRequest
from .params import RefereeParams
from .referee import MslReferee

__all__ = ["MslReferee", "OperatorError", "OperatorRequest", "RefereeParams"]
