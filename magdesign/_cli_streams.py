"""The ``magdesign`` command's streams and files: strict JSON on stdout, output paths checked
before the work, an error as one line on stderr (and one JSON object on stdout with --json),
a stdout that fails (a closed pipe, a full disk) told apart from other files, warnings as one
line, and a Ctrl-C that lands where Python cannot raise it. Used by :mod:`magdesign.cli`."""

import json
import math
import os
import sys
from pathlib import Path

from magdesign import _progress
from magdesign.units import SpecError


def json_text(value) -> str:
    """``value`` as strict JSON: a non-finite number (which json.dumps would write as the
    bare, invalid NaN or Infinity) becomes null."""

    def finite(item):
        if isinstance(item, float):
            return item if math.isfinite(item) else None
        if isinstance(item, dict):
            return {key: finite(entry) for key, entry in item.items()}
        if isinstance(item, (list, tuple)):
            return [finite(entry) for entry in item]
        return item

    return json.dumps(finite(value), allow_nan=False)


def check_output_path(path, option="--plot", suffix=".png"):
    """SpecError unless ``path`` is a file that can be written (checked before any work, so
    that a long run does not end in an error): a name ending in ``suffix``, no longer than
    its folder's file system takes, in an existing folder, and not a folder itself. The
    write is tried: a new file is made and removed at once, an existing one opened to append
    (unchanged), since permissions alone do not tell (root may "write" in /proc and /sys)."""
    target = Path(path)
    folder = target.parent
    try:
        longest = os.pathconf(folder, "PC_NAME_MAX")
    except (OSError, ValueError):
        longest = 255
    if len(os.fsencode(target.name)) > longest:
        raise SpecError(f"{option}: a file name of {len(os.fsencode(target.name))} bytes; at most {longest} there")
    if target.is_dir():
        raise SpecError(f"{option} {path}: a folder; give the path of the {suffix} file to write")
    if target.suffix.lower() != suffix:
        raise SpecError(f"{option} {path}: give a file name ending in {suffix}")
    if not folder.is_dir():
        raise SpecError(f"{option} {path}: no folder {folder}")
    if target.exists() and not target.is_file():
        raise SpecError(f"{option} {path}: not a regular file")
    try:
        if target.exists():
            with open(target, "ab"):
                pass
        else:
            with open(target, "xb"):
                pass
            target.unlink()
    except OSError as error:
        raise SpecError(f"{option} {path}: cannot write there ({error.strerror})") from None


def fail(args, code, kind, message):
    """One line on stderr; with --json also one JSON object on stdout (its reader wants one,
    if it is still there)."""
    print(f"magdesign {args.command}: {message}", file=sys.stderr)
    if getattr(args, "json", False):
        try:
            print(json_text({"error": kind, "message": message, "exit_code": code}), flush=True)
        except (OSError, StdoutFailed):
            drop_stdout()
    return code


def drop_stdout():
    """Send what is left for stdout to the null device, so that Python's last flush at exit
    does not fail again on a closed or full stdout."""
    try:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # a stdout without a file descriptor (a test's capture)
        pass


class StdoutFailed(Exception):
    """A write to stdout failed (``error``: a closed pipe, a full disk), told apart from
    the failures of other files."""

    def __init__(self, error):
        super().__init__(str(error))
        self.error = error


class Stdout:
    """``stream`` (sys.stdout) whose write errors raise :class:`StdoutFailed`."""

    def __init__(self, stream):
        self._stream = stream

    def write(self, text):
        try:
            return self._stream.write(text)
        except OSError as error:
            raise StdoutFailed(error) from None

    def flush(self):
        try:
            self._stream.flush()
        except OSError as error:
            raise StdoutFailed(error) from None

    def __getattr__(self, name):
        return getattr(self._stream, name)


def show_warnings_once():
    """A ``warnings.showwarning`` for one command: each warning as one line on stderr
    ("magdesign: warning: ..."), without a source line, and each message once. A command
    builds its scene more than once (a solve's error estimate, each candidate grid), and
    Python's once-per-place rule forgets what it said whenever a ``catch_warnings`` block
    ends, so the command keeps its own record."""
    shown = set()

    def show_warning(message, category, filename, lineno, file=None, line=None):
        if str(message) not in shown:
            shown.add(str(message))
            print(f"magdesign: warning: {message}", file=sys.stderr if file is None else file)

    return show_warning


def note_unraisable(report):
    """sys.unraisablehook during a command: a Ctrl-C that lands in a callback Python cannot
    raise from (JAX's garbage-collection callback) is noted, not printed, and raised again
    at the next stage line, file or the command's end; anything else is reported as usual."""
    if issubclass(report.exc_type, KeyboardInterrupt):
        _progress.swallowed_interrupt()
    else:
        sys.__unraisablehook__(report)
