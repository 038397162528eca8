"""The web subsystem: the coach machine of each team, the referee console and the replay page, in a
browser (paper section V-A: command area, display area, status area).

It reads the run only through the bus (`observer`), commands it only through the run's coaches and
Gazebo-like calls inside the lockstep (`control`), and serves pages and WebSockets from a thread of its
own (`server`). `LiveView` attaches all of it to an embedded `Simulation`; `ViewExtension` is the
``--view`` option of ``simatch run``.
"""

from .access import Access, Grant
from .live import LiveView

__all__ = ["Access", "Grant", "LiveView"]
