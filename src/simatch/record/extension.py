"""``--record FILE.mcap``: the run extension that records a run (``simatch run``, and any command that
takes the run options and attaches `simatch.cli.run.EXTENSIONS` to a `Simulation`, e.g. a server).

The recording starts before the first step and is finalised when the run ends, normally or by Ctrl-C
(SIGINT) or SIGTERM, which the extension turns into the same clean stop. A process killed outright
(SIGKILL) leaves every simulated second recorded before the one in progress (see `simatch.record.layout`).
"""

from __future__ import annotations

import contextlib
import signal
import sys

from ..errors import UsageError


class RecordExtension:
    def add_arguments(self, parser) -> None:
        group = parser.add_argument_group("recording")
        group.add_argument(
            "--record",
            metavar="FILE.mcap|DIR/",
            help="record every topic of the run, the 3D scene and the metadata needed to reproduce "
            "it into one MCAP file (rosbag2-compatible; see 'simatch replay', 'simatch export'); "
            "DIR/ (a trailing slash): a rosbag2 folder, DIR/DIR_0.mcap and its metadata.yaml",
        )
        group.add_argument(
            "--record-links",
            action="store_true",
            help="also record link states (every wheel) at the physics rate (slows the run down several times)",
        )

    def attach(self, sim, args):
        path = getattr(args, "record", None)
        if not path:
            return contextlib.nullcontext()
        return _recording(sim, path, getattr(args, "record_links", False))


class _Terminated(BaseException):
    """SIGTERM, raised in the main thread (at a step boundary while the run steps) so that the recording is
    finalised on the way out."""


@contextlib.contextmanager
def _recording(sim, path: str, links: bool):
    from . import rosbag2
    from .recorder import Recorder, RecordError

    try:
        folder = rosbag2.is_folder(path)
        file = rosbag2.prepare(path) if folder else path
        recorder = Recorder.for_run(
            sim, file, links=links, command_line=["simatch"] + sys.argv[1:], rosbag2_folder=folder
        )
    except (RecordError, rosbag2.Rosbag2Error) as exc:
        raise UsageError(str(exc)) from None
    try:
        with sim.stopping_on(signal.SIGTERM, _Terminated):
            yield recorder
    except _Terminated:
        recorder.close("terminated")
        raise SystemExit(128 + signal.SIGTERM) from None
    except KeyboardInterrupt:
        recorder.close("interrupted")
        raise
    except BaseException as exc:
        recorder.close(f"failed: {type(exc).__name__}: {exc}")
        raise
    finally:
        recorder.close("complete")
