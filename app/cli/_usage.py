"""The command line's name and its usage error: what ``app.cli`` needs before a subcommand is chosen.

Apart from ``_args`` (which re-exports both), so that importing ``app.cli`` imports no numpy:
``python -m app.cli`` turns the garbage collector off for its start-up (``_process``) only once
the package is imported, and the subcommand's imports then run without collections.
"""
from __future__ import annotations

PROG = "isoforce"


class UsageError(ValueError):
    """Bad command-line input: reported as one line on stderr with exit status 2."""
