import os
from pathlib import Path

import jax
import pytest

from magdesign._cache import use_compilation_cache

# One persistent compilation cache for the tests, in the repository's .pytest_cache (never
# the user's): the xdist workers, each module after clear_caches below and the commands the
# tests start load the programs that another one compiled. tests/test_cli.py checks the
# cache itself with folders of its own.
os.environ.setdefault("MAGDESIGN_CACHE_DIR", str(Path(__file__).resolve().parent.parent / ".pytest_cache" / "jax"))
jax.config.update("jax_enable_x64", True)
use_compilation_cache()


@pytest.fixture(autouse=True, scope="module")
def _drop_compiled_programs_after_each_module():
    """Free the programs a test module compiled once it is done: kept for the whole run,
    they add up to several GB in one test worker."""
    yield
    jax.clear_caches()


def mapped_regions():
    """(regions, limit): how many memory mappings this process holds and the most that
    Linux allows one process (vm.max_map_count); None where /proc cannot tell."""
    try:
        with open("/proc/sys/vm/max_map_count") as limit, open("/proc/self/maps", "rb") as maps:
            return sum(1 for _ in maps), int(limit.read())
    except (OSError, ValueError):
        return None


@pytest.fixture(autouse=True)
def _drop_compiled_programs_before_the_mapping_limit():
    """Free the compiled programs once they hold half the mappings a process may have.
    XLA:CPU's fusion emitters (jaxlib 0.12's only code generator) load each kernel as an
    object of its own, three mappings apiece: one design solve adds about 1,300, so a
    module of 50 solves reaches Linux's default limit (65,530), where XLA's next program
    fails to load ("Failed to materialize symbols")."""
    yield
    regions = mapped_regions()
    if regions is not None and regions[0] > regions[1] // 2:
        jax.clear_caches()


# Modules that take minutes of one worker, run first: with `-n 2 --dist loadscope` (the
# Makefile) each module runs on one worker, so that its module fixtures (a study's run, a
# compiled program) run once, and a long module started last would leave the other worker idle.
LONG_MODULES = ("tests/test_cli.py", "tests/studies/", "tests/test_docs.py", "tests/test_installed.py")


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    root = Path(__file__).resolve().parent.parent
    modules = {id(item): Path(item.fspath).resolve().relative_to(root).as_posix() for item in items}
    items.sort(key=lambda item: not modules[id(item)].startswith(LONG_MODULES))
