"""Recordings as rosbag2 folders: the MCAP file and, beside it, the ``metadata.yaml`` that ``ros2 bag`` writes.

A simatch recording is already a rosbag2 MCAP file (profile ``ros2``, ``ros2msg`` schemas, CDR), but ROS 2's
bag tools and ``rosbags``' ``AnyReader`` open a *folder* and read its ``metadata.yaml`` first (on a folder
with the ``.mcap`` alone, AnyReader fails with "Expected metadata file ... does not exist"). So:

* ``simatch run ... --record DIR/`` (a name ending in ``/``, or an empty folder) records into
  ``DIR/DIR_0.mcap`` (the name ``ros2 bag record -o DIR`` gives its first file) and writes
  ``DIR/metadata.yaml`` when the recording is finalised;
* ``simatch export FILE.mcap --format rosbag2 [-o DIR]`` makes such a folder of an existing recording (the
  file copied, the metadata counted from it);
* simatch's own commands take the folder wherever they take a recording (`recording_in`: its one ``.mcap``);
  a folder whose run was killed before it wrote ``metadata.yaml`` (the writer process still finalised the
  file) gets it from ``simatch recover DIR`` or ``simatch export DIR --format rosbag2`` (`complete`).

The metadata is rosbag2's version 9 (what Jazzy and later write): per channel its topic, type, ``cdr``, the
type's RIHS01 hash, and message counts; times are the recording's log times (simulated nanoseconds from 0).
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterable
from pathlib import Path

from .. import msgs
from . import foxglove_msgs as fg
from . import layout

METADATA = "metadata.yaml"
VERSION = 9


class Rosbag2Error(Exception):
    """A folder that cannot be made (it exists and is not empty, or a file cannot be read or written)."""


def is_folder(target: str | os.PathLike) -> bool:
    """A recording target that names a rosbag2 folder: ``DIR/`` or an existing empty folder."""
    text = os.fspath(target)
    path = Path(text)
    return text.endswith(("/", os.sep)) or (path.is_dir() and not any(path.iterdir()))


#: what simatch's commands say of a folder that is no rosbag2 recording
NOT_ONE = "a folder without exactly one .mcap recording in it"


def recording_in(path: str | os.PathLike) -> Path:
    """The recording file of ``path``: a file as it is, a folder's one ``.mcap`` file (a rosbag2 folder written
    by ``--record DIR/`` or by ``ros2 bag``); a folder with none or several is returned as it is (the reader
    then says it is no recording)."""
    path = Path(path)
    if path.is_dir():
        files = sorted(p for p in path.glob("*.mcap") if p.is_file())
        if len(files) == 1:
            return files[0]
    return path


def beside(path: str | os.PathLike, suffix: str) -> Path:
    """Where an output of the recording ``path`` goes by default: beside it, named after it with ``suffix``
    (``.html``, ``.bag``, ``_tables``) in place of ``.mcap``; for a rosbag2 folder, beside the folder (which
    keeps the bag alone), named after the folder."""
    path = Path(path)
    if path.is_dir():
        path = path.resolve()
        return path.with_name(path.name + suffix)
    return path.with_name(path.stem + suffix)


def complete(folder: str | os.PathLike) -> Path:
    """(Re)write the ``metadata.yaml`` of a folder holding one recording, counted from the file (a run killed
    before it wrote it); returns the metadata's path."""
    folder = Path(folder)
    mcap = recording_in(folder)
    if mcap == folder:
        raise Rosbag2Error(f"{folder}: {NOT_ONE}")
    channels, start, end = scan(mcap)
    try:
        return write_metadata(folder, mcap.name, channels, start, end)
    except OSError as exc:
        raise Rosbag2Error(f"cannot write {folder / METADATA}: {exc}") from None


def prepare(folder: str | os.PathLike) -> Path:
    """Make the folder (its parent must exist; it must not exist or be empty); returns the MCAP file's path."""
    folder = Path(os.fspath(folder).rstrip("/" + os.sep) or ".")
    if folder.exists() and (not folder.is_dir() or any(folder.iterdir())):
        raise Rosbag2Error(f"{folder} already exists and is not an empty folder (nothing was overwritten)")
    if not folder.parent.is_dir():
        raise Rosbag2Error(f"cannot make {folder}: folder {folder.parent} does not exist")
    folder.mkdir(exist_ok=True)
    return folder / f"{folder.resolve().name}_0.mcap"


def type_hash(typename: str) -> str:
    for store in (msgs.typestore, fg.typestore):
        if typename in store.fielddefs:
            return store.hash_rihs01(typename)
    return ""


def write_metadata(
    folder: Path, mcap_name: str, channels: Iterable[tuple[str, str, str, int]], start_ns: int, end_ns: int
) -> Path:
    """``metadata.yaml`` for ``channels`` (topic, type, RIHS01 hash, messages) of the file ``mcap_name``."""
    channels = list(channels)
    count = sum(n for *_, n in channels)
    duration = max(0, int(end_ns) - int(start_ns))
    info = {
        "version": VERSION,
        "storage_identifier": "mcap",
        "relative_file_paths": [mcap_name],
        "duration": {"nanoseconds": duration},
        "starting_time": {"nanoseconds_since_epoch": int(start_ns)},
        "message_count": count,
        "topics_with_message_count": [
            {
                "topic_metadata": {
                    "name": topic,
                    "type": typename,
                    "serialization_format": layout.MESSAGE_ENCODING,
                    "offered_qos_profiles": [],
                    "type_description_hash": digest,
                },
                "message_count": n,
            }
            for topic, typename, digest, n in channels
        ],
        "compression_format": "",
        "compression_mode": "",
        "files": [
            {
                "path": mcap_name,
                "starting_time": {"nanoseconds_since_epoch": int(start_ns)},
                "duration": {"nanoseconds": duration},
                "message_count": count,
            }
        ],
        "custom_data": {"simatch_recording": layout.FORMAT_VERSION},
        "ros_distro": "simatch",
    }
    from ruamel.yaml import YAML

    yaml = YAML(typ="safe")
    yaml.default_flow_style = False
    yaml.width = 4096  # a type hash on its key's line, as ros2 bag writes it (a folded one is valid YAML too)
    path = folder / METADATA
    tmp = path.with_suffix(".yaml.tmp")
    with open(tmp, "w", encoding="utf-8") as f:
        yaml.dump({"rosbag2_bagfile_information": info}, f)
    tmp.replace(path)
    return path


def scan(mcap_path: Path) -> tuple[list[tuple[str, str, str, int]], int, int]:
    """Every channel of an MCAP file with its message count, and the first and last log times."""
    from mcap.reader import make_reader

    counts: dict[int, list] = {}
    start, end = None, 0
    try:
        with open(mcap_path, "rb") as f:
            for schema, channel, message in make_reader(f).iter_messages():
                entry = counts.get(channel.id)
                if entry is None:
                    name = schema.name if schema is not None else ""
                    entry = counts[channel.id] = [channel.topic, name, type_hash(name), 0]
                entry[3] += 1
                t = message.log_time
                start = t if start is None else min(start, t)
                end = max(end, t)
    except Exception as exc:  # a damaged or unfinalised file: say which, never half a folder
        raise Rosbag2Error(f"{mcap_path} cannot be read to the end ({type(exc).__name__}: {exc})") from None
    return [tuple(v) for _, v in sorted(counts.items())], start or 0, end


def export(mcap_path: str | os.PathLike, folder: str | os.PathLike | None = None) -> Path:
    """A rosbag2 folder of the recording ``mcap_path`` (default: beside it, named after it); returns it. Given
    a folder that holds a recording already (and no other ``folder``), its metadata is written in place."""
    src = Path(mcap_path)
    if src.is_dir() and (folder is None or Path(folder).resolve() == src.resolve()):
        complete(src)
        return src
    if not src.is_file():
        raise Rosbag2Error(f"{src} does not exist")
    target = Path(folder) if folder is not None else src.with_suffix("")
    channels, start, end = scan(src)
    dst = prepare(target)
    try:
        shutil.copyfile(src, dst)
        write_metadata(dst.parent, dst.name, channels, start, end)
    except OSError as exc:
        raise Rosbag2Error(f"cannot write {dst.parent}: {exc}") from None
    return dst.parent
