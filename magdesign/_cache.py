"""Where the command keeps its programs: JAX's persistent compilation cache, in a folder per
CPU, and beside it the exported programs (:mod:`magdesign._export`)."""

import hashlib
import os
import platform
from pathlib import Path

import jax

# Programs that took longer than this to compile are kept in the persistent cache (JAX's own
# JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS, when set, wins).
CACHE_MIN_COMPILE_SECONDS = 0.5


def cpu_tag():
    """The machine's architecture and a hash of its CPU's instruction-set flags, e.g.
    "x86_64-3f9a0c2b71de". JAX's cache key leaves the CPU out, and a program compiled on one
    CPU may use instructions another lacks (a home folder shared by a cluster's machines)."""
    try:
        with open("/proc/cpuinfo") as cpuinfo:
            flags = next((line for line in cpuinfo if line.split(":")[0].strip() in ("flags", "Features")), "")
    except OSError:
        flags = platform.processor()
    return f"{platform.machine()}-{hashlib.sha256(flags.encode()).hexdigest()[:12]}"


def cache_directory():
    """Where the command keeps compiled programs (JAX's persistent compilation cache): the
    folder :func:`cpu_tag` names in $MAGDESIGN_CACHE_DIR, else in $XDG_CACHE_HOME/magdesign/jax,
    else in ~/.cache/magdesign/jax; None when MAGDESIGN_NO_CACHE is set to anything but "" or "0"."""
    if os.environ.get("MAGDESIGN_NO_CACHE", "") not in ("", "0"):
        return None
    if os.environ.get("MAGDESIGN_CACHE_DIR"):
        return Path(os.environ["MAGDESIGN_CACHE_DIR"]) / cpu_tag()
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "magdesign" / "jax" / cpu_tag()


def export_directory(directory):
    """Where the command keeps its exported programs (:mod:`magdesign._export`), beside
    the compiled programs' ``directory`` (:func:`cache_directory`, a CPU's folder): the
    same CPU's folder in the folder "exported" next to it."""
    return directory.parent / "exported" / directory.name


def use_compilation_cache(debug=False):
    """Turn on JAX's persistent compilation cache (see :func:`cache_directory`), so that a
    second run of the same command reuses the programs the first compiled. Unless ``debug``,
    XLA's C++ log is kept to fatal errors: loading a program from the cache logs an error
    that the compiling CPU's tuning features (such as +prefer-no-gather) are not the host's
    instructions, "could lead to ... SIGILL", for every program, although it is the same CPU
    (:func:`cpu_tag`). XLA's failures still reach the command as exceptions."""
    directory = cache_directory()
    if directory is None:
        return
    jax.config.update("jax_compilation_cache_dir", str(directory))
    if "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS" not in os.environ:
        jax.config.update("jax_persistent_cache_min_compile_time_secs", CACHE_MIN_COMPILE_SECONDS)
    if not debug:
        jax.config.update("jax_logging_level", "CRITICAL")
