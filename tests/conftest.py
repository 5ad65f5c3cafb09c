import os
from pathlib import Path

import jax
import pytest

from magdesign._cache import use_compilation_cache
from magdesign._tracing import free_programs_near_mapping_limit

# One persistent compilation cache for the tests, in the repository's .pytest_cache (never
# the user's): the xdist workers, each module after clear_caches below and the commands the
# tests start load the programs that another one compiled. tests/test_cli.py checks the
# cache itself with folders of its own.
os.environ.setdefault("MAGDESIGN_CACHE_DIR", str(Path(__file__).resolve().parent.parent / ".pytest_cache" / "jax"))
# Every edit of magdesign makes the kept executables of the commands the tests run a miss
# (magdesign._export.versions) while JAX's cache holds the same programs: the tests load
# them from JAX's cache rather than compile each once more to keep it, which a user's
# command does after an upgrade (tests/test_export_cache.py and test_second_run.py check it).
os.environ.setdefault("MAGDESIGN_NO_RECOMPILE", "1")
jax.config.update("jax_enable_x64", True)
use_compilation_cache()


@pytest.fixture(autouse=True, scope="module")
def _drop_compiled_programs_after_each_module():
    """Free the programs a test module compiled once it is done: kept for the whole run,
    they add up to several GB in one test worker."""
    yield
    jax.clear_caches()


@pytest.fixture(autouse=True)
def _drop_compiled_programs_before_the_mapping_limit():
    """Free the compiled programs once they hold half the memory mappings a process may
    have (magdesign._tracing.free_programs_near_mapping_limit), after each test: the
    library checks before each design program it compiles, and a test module compiles
    many other programs too (fields, scenes, domes)."""
    yield
    free_programs_near_mapping_limit()


# Modules that take minutes of one worker, run first: with `-n 2 --dist loadscope
# --no-loadscope-reorder` (the Makefile) each module runs on one worker, in this order, so
# that its module fixtures (a study's run, a compiled program) run once, and a long module
# started last would leave the other worker idle.
LONG_MODULES = ("tests/test_cli.py", "tests/studies/", "tests/test_docs.py", "tests/test_installed.py")


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    root = Path(__file__).resolve().parent.parent
    modules = {id(item): Path(item.fspath).resolve().relative_to(root).as_posix() for item in items}
    items.sort(key=lambda item: not modules[id(item)].startswith(LONG_MODULES))
