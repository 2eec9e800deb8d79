"""``isoforce``: the headless command line, one module per subcommand.

::

    isoforce devices              list the shipped presets                          (devices)
    isoforce show DEVICE          every parameter with its name, unit and value     (show)
    isoforce stats DEVICE         global figures of the default map                 (stats)
    isoforce pose DEVICE --at P   everything about one pose (or --joints Q)          (pose)
    isoforce map DEVICE --quantity Q --out FILE    heat map (.png/.svg/.pdf) or data (.csv/.npz)   (map)
    isoforce compare DEVICE DEVICE ...   force figures of several devices side by side  (compare)
    isoforce figure | convergence | optimize | bench ...                            (one module each)

DEVICE is a preset key (``isoforce devices``) or a path to a ``.toml`` preset. Lengths are
typed and printed in mm, angles in deg, torques in N m, forces in N. ``isoforce`` with no
command starts the desktop app: that is ``app.launch``, so this package never imports the GUI.

Every subcommand module has a ``register(subparsers)`` function that adds its parser and
sets ``func``, which takes the parsed arguments and returns the exit status; ``_args`` holds
the shared validators and ``_format`` the shared output. Bad input (unknown device, bad
``--set``, bad ``--at``, bad file name) gives one line on stderr naming the argument, exit
status 2, and no partial file. With ``--json`` stdout holds exactly one JSON object (strict:
no ``NaN``; ``nan`` is ``null``, ``inf`` is ``"inf"``), and nothing at all when the command fails.
"""
from __future__ import annotations

import argparse
import importlib
import os
import signal
import sys
import threading
from typing import Callable, Sequence

from app.cli._process import start_up_over
from app.cli._usage import PROG, UsageError

#: The subcommands in the order ``--help`` lists them; each is the module ``app.cli.<name>``.
COMMANDS = ("devices", "show", "stats", "pose", "map", "convergence", "bench", "figure", "optimize",
            "compare", "dextrous", "spec")

__all__ = ["COMMANDS", "PROG", "UsageError", "build_parser", "main"]


class _Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors raise ``UsageError`` instead of printing usage and exiting.

    ``main`` turns that into the one-line message every other input error gets.
    """

    def error(self, message: str):  # type: ignore[override]
        raise UsageError(f"{message} (see `{self.prog} --help`)")


def _register(subparsers, command: str) -> bool:
    """Register the subcommand of ``app.cli.<command>``; if it cannot be imported, say why when it is used.

    Returns False when its module is not installed (the command does not exist), else True.
    """
    module_name = f"{__name__}.{command}"
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        if exc.name == module_name:
            return False     # the module is not installed: the command does not exist
        reason = str(exc)

        def unavailable(args: argparse.Namespace) -> int:
            raise UsageError(f"`{PROG} {command}` is unavailable: {reason}")

        p = subparsers.add_parser(command, help=f"(unavailable: {reason})", add_help=False)
        p.add_argument("rest", nargs=argparse.REMAINDER)
        p.set_defaults(func=unavailable)
        return True
    module.register(subparsers)
    return True


def build_parser(commands: Sequence[str] = COMMANDS) -> argparse.ArgumentParser:
    """The ``isoforce`` parser with the subcommands ``commands`` (default: every one) registered.

    Registering a subcommand imports its module (and what that imports: ``figure`` loads
    pyvista and matplotlib, ``optimize`` the design study): ``main`` registers only the one
    it runs (``_parser_for``), and every one where it needs the whole list.
    """
    return _build(commands)[0]


def _build(commands: Sequence[str]) -> tuple[argparse.ArgumentParser, bool]:
    """The parser with ``commands``, and whether every one of them registered."""
    parser = _Parser(prog=PROG, description="Force capability of haptic devices: maps, poses, statistics. "
                                            "With no arguments, launch the desktop app.")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    registered = [_register(subparsers, command) for command in commands]
    return parser, all(registered)


def _parser_for(argv: list[str]) -> argparse.ArgumentParser:
    """The parser for ``argv``: its command alone when it names one that registers, else every command.

    ``--help``, no command, a mistyped or a missing one get every command, so that the listing
    or the error's "choose from" is the whole one.
    """
    if argv and argv[0] in COMMANDS:
        parser, registered = _build((argv[0],))
        if registered:
            return parser
    return build_parser()


def _join_negative_values(argv: list[str], options: tuple[str, ...] = ("--at", "--joints", "--box")) -> list[str]:
    """``--at -10,150`` -> ``--at=-10,150`` (``--joints``, ``--box``): argparse would read ``-10,150`` as an option."""
    out: list[str] = []
    i = 0
    while i < len(argv):
        token = argv[i]
        nxt = argv[i + 1] if i + 1 < len(argv) else ""
        if token in options and len(nxt) > 1 and nxt[0] == "-" and (nxt[1].isdigit() or nxt[1] == "."):
            out.append(f"{token}={nxt}")
            i += 2
        else:
            out.append(token)
            i += 1
    return out


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread like Ctrl-C, so that every ``finally`` and atomic write
    cleans up on the way out (the default SIGTERM action kills the process on the spot)."""


def _on_sigterm(signum, frame) -> None:
    # A second SIGTERM during the clean-up must not interrupt it.
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    raise Terminated()


def _stop_workers() -> None:
    """After an interrupt or MemoryError: remove export temporaries, stop worker processes.

    Map threads need nothing: ``metrics.workspace`` keeps only a few chunks in flight, so they
    finish within a chunk once the main thread stops asking. Worker processes of a design study
    are stopped by ``app.cli.optimize``; any left (a pool made elsewhere) are terminated here,
    and the process pools' manager threads are let end.
    """
    from app.files.export import remove_temporaries

    remove_temporaries()
    if "multiprocessing" in sys.modules:
        import multiprocessing

        children = multiprocessing.active_children()
        for child in children:
            child.terminate()
        for child in children:
            child.join(timeout=2.0)
    if "concurrent.futures.process" in sys.modules:
        from concurrent.futures import process

        # A stopped process pool's manager thread closes its wake-up pipe as it ends, and the
        # interpreter's exit hook writes to that pipe: CPython 3.11 checks and writes without a
        # lock, so the two can cross (EBADF, a traceback on stderr after the one-line message,
        # seen once in CI). The threads are let end first; the hook then finds the pipes closed.
        for thread in list(getattr(process, "_threads_wakeups", {}).keys()):
            thread.join(timeout=2.0)


def _skip_the_final_collections() -> None:
    """At the interpreter's exit, leave the objects alive then out of its last garbage collections.

    A command that loaded a compiled kernel holds numba's objects (hundreds of thousands); the
    collections the interpreter runs as it finalizes traversed them all after the output was
    written: 0.10-0.22 s of ``isoforce convergence`` (0.03 s for numpy alone), 0.02 s with
    ``gc.freeze`` first (this machine, load 3), and about as much of ``stats`` and ``figure``.
    Registered with ``atexit``, once a process, so nothing changes while a command runs (a test
    calling ``main`` keeps its collections): the objects are still freed with the process; what
    a command writes is closed before, and the interpreter flushes stdout and stderr itself.
    """
    if not _FREEZE_AT_EXIT:
        import atexit
        import gc

        atexit.register(gc.freeze)
        _FREEZE_AT_EXIT.append(True)


#: Set once ``_skip_the_final_collections`` has registered its hook.
_FREEZE_AT_EXIT: list[bool] = []


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status.

    0 ok, 2 bad input, 1 out of memory, 130 Ctrl-C, 143 SIGTERM: each failure is one line on
    stderr, never a traceback, and leaves no partial or temporary file.
    """
    argv = list(sys.argv[1:] if argv is None else argv)
    _skip_the_final_collections()
    in_main_thread = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, _on_sigterm) if in_main_thread else None
    try:
        return _main(argv)
    finally:
        if in_main_thread:
            signal.signal(signal.SIGTERM, previous if previous is not None else signal.SIG_DFL)


def _main(argv: list[str]) -> int:
    parser = _parser_for(argv)
    command = "?"
    try:
        args = parser.parse_args(_join_negative_values(argv))
        command = args.command
        if command is None:
            raise UsageError("a COMMAND is needed")
        func: Callable[[argparse.Namespace], int] = args.func
        start_up_over()
        return int(func(args) or 0)
    except SystemExit as exc:            # --help, or a subcommand that exits itself
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 2)
    except KeyboardInterrupt as exc:     # Ctrl-C, or SIGTERM (Terminated)
        _stop_workers()
        where = f"{PROG} {command}" if command not in (None, "?") else PROG
        what = "terminated (SIGTERM)" if isinstance(exc, Terminated) else "interrupted (Ctrl-C)"
        print(f"{where}: {what}: stopped, no partial file left", file=sys.stderr)
        return 143 if isinstance(exc, Terminated) else 130
    except MemoryError:
        _stop_workers()
        where = f"{PROG} {command}" if command not in (None, "?") else PROG
        print(f"{where}: error: out of memory: stopped, no partial file left; try a smaller --resolution "
              f"or fewer quantities (ISOFORCE_MEMORY sets the memory the estimate may plan for)", file=sys.stderr)
        return 1
    except BrokenPipeError:
        # The reader went away (`isoforce pose ... | head`): not an error worth a message. Point
        # stdout at devnull so the interpreter's final flush does not complain (Python docs).
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    except (ValueError, OSError) as exc:
        # ValueError: bad input (UsageError, PresetError, a parameter or file name out of
        # range); OSError: the file system refused. One line, no traceback (set
        # ISOFORCE_DEBUG=1 to see one when a ValueError is a bug rather than bad input).
        if os.environ.get("ISOFORCE_DEBUG"):
            raise
        where = f"{PROG} {command}" if command not in (None, "?") else PROG
        print(f"{where}: error: {_one_line(exc)}", file=sys.stderr)
        return 2


def _one_line(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.strerror:
        return f"{exc.strerror}: {exc.filename}" if exc.filename else exc.strerror
    return " ".join(str(exc).split())


