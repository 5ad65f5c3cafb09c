"""Progress lines: what a long run of the command is doing, one line per stage on stderr.

The command turns the lines on (:func:`enable`) unless ``--quiet``; the library says its own
slow stages (a first compile, a measurement) through :func:`stage`, which prints nothing
until then, so that a Python program that calls the library stays silent. The lines go to
stderr, so that stdout holds only the command's answer (one JSON object with ``--json``).
Progress bars (tqdm) are separate: they show only on a terminal.
"""

import sys

_prefix = None  # "magdesign solve" while the lines are on; None: off
_swallowed = False  # a Ctrl-C that a callback caught and dropped


def enable(prefix: str | None) -> None:
    """Print stage lines as "PREFIX: message" from now on (None: print none); forget a
    swallowed interrupt."""
    global _prefix, _swallowed
    _prefix, _swallowed = prefix, False


def swallowed_interrupt() -> None:
    """Note a Ctrl-C that a callback caught and dropped (Python reports an exception in a
    garbage-collection callback or a __del__ and goes on): :func:`check_interrupt` raises
    it again at the next stage or file."""
    global _swallowed
    _swallowed = True


def check_interrupt() -> None:
    """Raise KeyboardInterrupt where a Ctrl-C was swallowed (:func:`swallowed_interrupt`)."""
    if _swallowed:
        raise KeyboardInterrupt


def stage(message: str) -> None:
    """One line on stderr saying what runs now ("magdesign sweep: solving 15 points ...")."""
    check_interrupt()
    say(f"{message} ...")


def wrote(path) -> None:
    """One line on stderr naming a file the command wrote ("magdesign solve: wrote design.png")."""
    say(f"wrote {path}")


def say(text: str) -> None:
    """One line on stderr as it is written ("magdesign accuracy: dome compliance, reissner: ...")."""
    # no stderr at all (a process started with it closed): print(file=None) would write to stdout
    if _prefix is not None and sys.stderr is not None:
        print(f"{_prefix}: {text}", file=sys.stderr, flush=True)
