"""What the test run's guard against Linux's limit on a process's memory mappings
(tests/conftest.py) relies on: compiled programs hold mappings, and jax.clear_caches()
gives them back."""

from pathlib import Path

import jax
import jax.numpy as jnp
import pytest

MAPS = Path("/proc/self/maps")
PROGRAMS = 20

pytestmark = pytest.mark.skipif(not MAPS.exists(), reason="no /proc/self/maps to count mappings in")


def regions():
    with MAPS.open("rb") as maps:
        return sum(1 for _ in maps)


def program(k):
    return jax.jit(lambda x: jnp.sin(k * x) + jnp.cos(x) ** k)  # k a constant of the program


def compile_and_run(first):
    """PROGRAMS programs that no other test has (``first`` names them), each compiled and
    run; they are kept, as JAX's caches keep them."""
    programs = [program(k) for k in range(first, first + PROGRAMS)]
    for each in programs:
        each(jnp.linspace(0.0, 1.0, 5)).block_until_ready()
    return programs


def test_clear_caches_gives_back_the_mappings_of_compiled_programs():
    # a first round sets up what stays (XLA's threads and their memory pools)
    compile_and_run(1)
    jax.clear_caches()
    before = regions()
    kept = compile_and_run(1 + PROGRAMS)
    grown = regions() - before
    jax.clear_caches()
    left = regions() - before
    assert len(kept) == PROGRAMS
    assert grown >= PROGRAMS  # each program's code is mapped
    assert left < grown / 4
