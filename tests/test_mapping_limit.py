"""The guard against Linux's limit on a process's memory mappings
(magdesign._tracing.free_programs_near_mapping_limit, also called by tests/conftest.py):
compiled programs hold mappings, jax.clear_caches() gives them back, and past half the
limit the library empties its caches of programs and still solves."""

from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from magdesign import _tracing
from magdesign.design import Objective, Problem, Variable, multistart, solve
from magdesign.design._sqp import batch
from magdesign.design._sqp.program import _compiled

MAPS = Path("/proc/self/maps")
PROGRAMS = 20
CENTRE = 0.3  # where (x - 0.3)^2 is least on [0, 1]: the parabola's vertex

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


def parabola_model(v):
    return {"f": (v["x"] - CENTRE) ** 2}


def parabola():
    """A problem of the structure that both tests solve (one model function: one program)."""
    return Problem(parabola_model, [Variable("x", 0.0, 1.0, start=0.9)], objective=Objective("f", "min"))


def solved_at_the_vertex(problem):
    one = solve(problem, start={"x": 0.1})
    assert one.status == "successful" and one.parameters["x"] == pytest.approx(CENTRE, abs=1e-6)


def test_past_half_the_limit_the_library_frees_its_programs_and_still_solves(monkeypatch):
    problem = parabola()
    solved_at_the_vertex(problem)
    many = multistart(problem, {"x": np.array([0.1, 0.9])})  # a batch program (batch._PROGRAMS)
    assert list(many.status) == ["successful"] * 2
    np.testing.assert_allclose(many.parameters["x"], CENTRE, atol=1e-6)
    assert _compiled.cache_info().currsize >= 1 and batch._PROGRAMS
    counted = _tracing.mapped_regions
    before = counted()[0]
    monkeypatch.setattr(_tracing, "mapped_regions", lambda: (counted()[0], 2))  # a limit every process passes
    assert _tracing.free_programs_near_mapping_limit() is True
    assert _compiled.cache_info().currsize == 0 and not batch._PROGRAMS
    assert counted()[0] < before  # the programs' mappings given back

    # each program compiled now first frees those before it; the solves still answer
    solved_at_the_vertex(problem)
    assert _compiled.cache_info().currsize >= 1


def test_below_half_the_limit_or_where_proc_cannot_tell_nothing_is_freed(monkeypatch):
    solved_at_the_vertex(parabola())
    counted = _tracing.mapped_regions
    monkeypatch.setattr(_tracing, "mapped_regions", lambda: None)
    assert _tracing.free_programs_near_mapping_limit() is False
    assert _compiled.cache_info().currsize >= 1
    monkeypatch.setattr(_tracing, "mapped_regions", lambda: (counted()[0], 4 * counted()[0]))
    assert _tracing.free_programs_near_mapping_limit() is False
    assert _compiled.cache_info().currsize >= 1
