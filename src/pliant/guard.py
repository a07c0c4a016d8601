"""The command line's outer guard: every outcome of a command becomes an exit code and at most one
line on stderr, never a traceback.

Exit codes (also in ``pliant --help`` and docs/scenes.md): 0 success; 1 the simulation failed
(:class:`~pliant.errors.InstabilityError`, :class:`~pliant.errors.ConvergenceError`) or a check
found problems; 2 bad input (:class:`~pliant.errors.InputError`, usage errors, and files the
operating system refuses to read or write); 3 an internal error, i.e. a bug in pliant: the line
names the exception and the log file that holds the full traceback; 130 interrupted (Ctrl-C, or
SIGTERM as a batch scheduler's time limit, ``timeout`` and ``kill`` send it: both end a run the same
way, its frames indexed and its summary written).

Python warnings are routed too: pliant's own (:class:`~pliant.errors.PliantWarning`, and
``UserWarning`` raised from pliant modules) are printed as one ``warning:`` line each; those of
libraries (numpy overflow and the like) are dropped. ``PLIANT_DEBUG=1`` prints tracebacks and every
warning, for developers.
"""

from __future__ import annotations

import contextlib
import datetime
import os
import signal
import sys
import tempfile
import traceback
import warnings
from typing import Any
from pathlib import Path

import typer
from rich.markup import escape

from .errors import InputError, PliantError, PliantWarning

EXIT_OK, EXIT_FAILED, EXIT_INPUT, EXIT_INTERNAL, EXIT_INTERRUPTED = 0, 1, 2, 3, 130

Abort = typer.Abort
# Usage errors: click's ClickException (vendored inside typer in recent versions, click's own in
# older ones); found from a public class so that no private module path is named.
ClickException: Any = next(c for c in typer.BadParameter.__mro__ if c.__name__ == "ClickException")


def _debug() -> bool:
    return os.environ.get("PLIANT_DEBUG", "") not in ("", "0")


def crash_log(exc: BaseException, argv: list[str]) -> Path | None:
    """Write the traceback of ``exc`` with the command line to a new file in the temp folder;
    returns its path (None if even that cannot be written)."""
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    try:
        fd, name = tempfile.mkstemp(prefix=f"pliant-crash-{stamp}-", suffix=".log")
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write("pliant " + " ".join(argv) + "\n\n")
            f.write("".join(traceback.format_exception(type(exc), exc, exc.__traceback__)))
        return Path(name)
    except OSError:
        return None


def one_line(text: str, limit: int = 2000) -> str:
    """A message as one line: newlines folded, capped at ``limit`` characters (a hostile input can
    carry megabytes into an error message)."""
    s = " ".join(str(text).split())
    return s if len(s) <= limit else s[: limit - 20] + f" ... [{len(s) - limit + 20} more characters]"


@contextlib.contextmanager
def routed_warnings(console):
    """pliant's own warnings as ``warning:`` lines, other libraries' warnings silenced (kept in
    the debug output with PLIANT_DEBUG=1)."""
    old = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        ours = "pliant" in Path(str(filename)).parts or issubclass(category, PliantWarning)
        if ours and issubclass(category, UserWarning):
            console.print(
                f"[yellow]warning:[/] {escape(one_line(str(message)))}", highlight=False, markup=True
            )
        elif _debug():
            old(message, category, filename, lineno, file, line)

    with warnings.catch_warnings():
        warnings.simplefilter("default")
        warnings.showwarning = show
        try:
            yield
        finally:
            warnings.showwarning = old


def _interrupt(signum, frame):
    raise KeyboardInterrupt


@contextlib.contextmanager
def terminate_as_interrupt():
    """SIGTERM raises KeyboardInterrupt in the main thread while the block runs, so that a
    terminated command ends as an interrupted one (Python's default for SIGTERM ends the process
    at once: no summary, no message). Main thread only (elsewhere a plain block)."""
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGTERM, _interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


def run_guarded(app, argv: list[str] | None, console) -> int:
    """Run the typer ``app`` on ``argv`` (default sys.argv[1:]); returns the exit code."""
    argv = list(sys.argv[1:] if argv is None else argv)

    def say(msg: str):
        console.print(f"[bold red]error:[/] {escape(one_line(msg))}", highlight=False, markup=True)

    with routed_warnings(console), terminate_as_interrupt():
        try:
            rv = app(args=argv, standalone_mode=False, prog_name="pliant")
            return rv if isinstance(rv, int) else EXIT_OK
        except ClickException as e:  # usage errors: click's own message (exit 2)
            e.show()
            return e.exit_code
        except (Abort, KeyboardInterrupt):
            console.print("interrupted")
            return EXIT_INTERRUPTED
        except BrokenPipeError:  # `pliant info | head`
            with contextlib.suppress(Exception):
                sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - no flush error at exit
            return EXIT_OK
        except InputError as e:
            say(str(e))
            return EXIT_INPUT
        except PliantError as e:
            say(str(e))
            return EXIT_FAILED
        except OSError as e:  # the file system refused: permissions, a full disk, a vanished file
            where = f"{e.filename}: " if getattr(e, "filename", None) else ""
            say(f"{where}{e.strerror or e}")
            return EXIT_INPUT
        except RecursionError as e:  # deep structures in input files
            say(f"input nested too deeply to process ({e})")
            return EXIT_INPUT
        except MemoryError:
            say(
                "out of memory: the input asks for more memory than this machine has (a mesh, "
                "a step count or an output too large?)"
            )
            return EXIT_INPUT
        except Exception as e:  # a bug: one line, the traceback in a file
            if _debug():
                traceback.print_exc()
            log = crash_log(e, argv)
            where = f"full traceback in {log}" if log else "no log could be written"
            say(
                f"internal error in 'pliant {' '.join(argv[:1])}': {type(e).__name__}: "
                f"{one_line(str(e), 300)} ({where}; please report it)"
            )
            return EXIT_INTERNAL
