"""The web subsystem: the coach machine of each team, the referee console and the replay page, in a
browser (paper section V-A: command area, display area, status area).

It reads a run only through the bus (`observer`), commands it only through calls that a recording keeps —
the referee's operator interface on the bus, the teams' coaches, the Simulation API — inside the lockstep
(`control`), and serves pages and WebSockets from a thread of its own (`server`). `LiveView` attaches all
of it to an embedded `Simulation`, `RecordingView` to a recording played back on a bus; `view` holds the
``--view`` options of ``simatch run`` and ``simatch replay``.
"""

from .access import Access, Grant
from .live import LiveView
from .recorded import RecordingView

__all__ = ["Access", "Grant", "LiveView", "RecordingView"]
