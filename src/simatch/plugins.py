"""Plug-ins named in scene files: a shipped short name or ``"package.module:Class"``.

Robot models, strategies and judges are all chosen this way; each subsystem keeps its own table of
shipped names and calls `load` with it.
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from typing import Any


class PluginError(ValueError):
    """A plug-in that cannot be found or loaded; the message says which and why."""


def load(spec: str, shipped: Mapping[str, str], what: str) -> Any:
    """The object named by ``spec``: a key of ``shipped`` or ``package.module:attribute``."""
    target = shipped.get(spec, spec)
    module_name, sep, attr = target.partition(":")
    if not sep or not module_name or not attr:
        raise PluginError(
            f"unknown {what} {spec!r}: expected one of {', '.join(sorted(shipped))} or 'package.module:Class'"
        )
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise PluginError(f"{what} {spec!r}: cannot import module {module_name!r} ({exc})") from None
    except Exception as exc:  # a user module that fails while importing
        raise PluginError(
            f"{what} {spec!r}: module {module_name!r} fails to import: {type(exc).__name__}: {exc}"
        ) from None
    obj = module
    for part in attr.split("."):
        try:
            obj = getattr(obj, part)
        except AttributeError:
            raise PluginError(f"{what} {spec!r}: module {module_name!r} has no {attr!r}") from None
    return obj
