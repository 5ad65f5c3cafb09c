import os

import jax
import pytest

# The command's persistent compilation cache stays out of the tests (tests/test_cli.py
# checks it with its own folder).
os.environ.setdefault("MAGDESIGN_NO_CACHE", "1")
jax.config.update("jax_enable_x64", True)


@pytest.fixture(autouse=True, scope="module")
def _drop_compiled_programs_after_each_module():
    """Free the programs a test module compiled once it is done: kept for the whole run,
    they add up to several GB in one test worker."""
    yield
    jax.clear_caches()
