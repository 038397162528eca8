"""Errors every layer may raise and the command line prints as one line, without a traceback.

They live here, below the subsystems, so that an extension of a run (recording, viewing) can refuse a
command line without importing the command-line package that sits above it.
"""

from __future__ import annotations


class UsageError(Exception):
    """A command line that cannot be carried out; printed without a traceback."""
