"""Files that magdesign writes: each whole or not at all."""

import contextlib
import os
import secrets
from pathlib import Path

from magdesign._progress import check_interrupt


@contextlib.contextmanager
def replaced(path):
    """A new hidden path beside ``path``, with its suffix (which picks a picture's format),
    to write the file to: renamed over ``path`` when the block ends, removed when it raises
    (an interrupt included, :func:`magdesign._progress.check_interrupt`), so that a failure
    leaves the old file or none, never half a file."""
    path = Path(path)
    temporary = path.with_name(f".{path.stem}.{secrets.token_hex(4)}{path.suffix}")
    try:
        yield temporary
        check_interrupt()  # a Ctrl-C swallowed while the file was written
        os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(temporary)
        raise
