"""The exported programs and compiled executables kept on disk (magdesign._export): one
entry per structure, the spec's numbers arguments of it, executables read back by a new
process, damaged or stale entries made again, a switch to turn it off."""

import copy
import json
import os
import pickle
import shutil
import subprocess
import sys
import textwrap

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax._src import compilation_cache

from magdesign import _export, cli
from magdesign._tracing import errors_as_nan
from magdesign.design import solve
from magdesign.design._sqp.program import _compiled, _host, _structure, settings_of
from magdesign.spec.design import default_spec, problem_from_spec


@pytest.fixture
def kept(tmp_path, monkeypatch):
    """Exported programs kept in a fresh folder for the test, then as they were."""
    monkeypatch.delenv("MAGDESIGN_NO_EXPORT", raising=False)
    saved = _export.directory()
    _export.enable(tmp_path / "exported")
    _new_process()
    yield tmp_path / "exported"
    _export.enable(saved)
    _export._KEPT.clear()
    _export._LOADED.clear()


def _new_process():
    """Forget every program this process traced or read, as a new process starts."""
    jax.clear_caches()
    _compiled.cache_clear()
    _export._KEPT.clear()
    _export._LOADED.clear()


def _entries(folder, name):
    return sorted(path.name for path in folder.glob(f"{name}-*.jaxexport"))


def _spec(compliance="0.32 mm/N", remanence="1.17 T", c10="0.1182 MPa"):
    spec = copy.deepcopy(default_spec())
    spec["design"]["targets"]["compliance"] = compliance
    spec["magnet"]["remanence"] = remanence
    spec["mechanics"]["c10"] = c10
    return spec


def _solved(spec):
    return solve(problem_from_spec(spec, fidelity="reissner")[0])


@pytest.mark.slow
def test_specs_that_differ_in_numbers_share_one_entry_and_keep_their_own_answers(kept):
    first, other = _spec(), _spec(compliance="0.3 mm/N", remanence="1.25 T", c10="0.13 MPa")
    exported = [_solved(first)]
    _new_process()  # the second spec reads the first one's entry from disk
    exported.append(_solved(other))
    assert len(_entries(kept, "solve")) == 1
    _export.enable(None)
    _new_process()
    plain = [_solved(first), _solved(other)]
    for via_entry, traced in zip(exported, plain):
        assert via_entry.status == traced.status == "successful" and via_entry.steps == traced.steps
        for name, value in traced.parameters.items():
            np.testing.assert_allclose(via_entry.parameters[name], value, rtol=1e-12)
    # each meets its own target (0.32 and 0.30 mm/N), so neither ran the other's numbers
    for result, wanted in zip(exported, (0.32e-3, 0.30e-3)):
        np.testing.assert_allclose(result.targets["compliance"]["achieved"], wanted, rtol=1e-9)
    assert exported[0].parameters["geometry.gap"] != exported[1].parameters["geometry.gap"]


@pytest.mark.slow
def test_a_structural_change_makes_a_new_entry(kept):
    def lowered(spec):  # traced and exported, not compiled
        problem = problem_from_spec(spec, fidelity="reissner")[0]
        key, arrays = _structure(problem, settings_of(1e-10, 1e-13, 100))
        with errors_as_nan():
            _compiled(key, False).lower(arrays, _host(problem).y0, _host(problem).theta)

    lowered(_spec())
    lowered(_spec(compliance="0.3 mm/N"))
    assert len(_entries(kept, "solve")) == 1
    fewer = _spec()
    fewer["scene"]["effects"] = ["saturation"]  # no quantisation: another chain
    lowered(fewer)
    assert len(_entries(kept, "solve")) == 2


def _toy(kept):
    """A kept program of 2 sin(x) and its one entry's path."""
    _new_process()
    program = _export.jit(lambda x: 2.0 * jnp.sin(x), "toy", "2 sin(x)")
    value = program(jnp.asarray([0.5, 1.0]))
    return value, kept / _entries(kept, "toy")[0]


# A new process that keeps a program (the eigenvalues of a symmetric matrix, LAPACK's, times
# a) in the folder argv[1], calls it and prints its answer and how many programs it compiled.
_NEW_PROCESS = textwrap.dedent(
    """
    import json, sys
    import jax, jax.numpy as jnp, numpy as np
    jax.config.update("jax_enable_x64", True)
    from magdesign import _export
    compiled = []
    jax.monitoring.register_event_duration_secs_listener(
        lambda event, seconds, **kwargs: compiled.append(event) if event.endswith("backend_compile_duration") else None
    )
    _export.enable(sys.argv[1])
    program = _export.jit(lambda a, m: a * jnp.linalg.eigvalsh(m), "toy-eig", "a eigvalsh(m)")
    m = np.array([[2.0, 1.0, 0.0], [1.0, 2.0, 1.0], [0.0, 1.0, 2.0]])
    batch = program.lower(np.asarray(3.0), jax.ShapeDtypeStruct((3, 3), jnp.float64)).compile()
    print(json.dumps({"value": program(np.asarray(3.0), m).tolist(), "batch": batch(np.asarray(3.0), m).tolist(),
                      "compiled": len(compiled)}))
    """
)


def _run_new_process(folder, **environment):
    done = subprocess.run(
        [sys.executable, "-c", _NEW_PROCESS, str(folder)],
        capture_output=True,
        text=True,
        check=True,
        env={**os.environ, **environment},
    )
    return json.loads(done.stdout.splitlines()[-1])


def _events():
    """The names of JAX's monitoring events (plain and timed) while the block runs."""
    heard = []

    def event(name, **kwargs):
        heard.append(name)

    def timed(name, seconds, **kwargs):
        heard.append(name)

    jax.monitoring.register_event_listener(event)
    jax.monitoring.register_event_duration_secs_listener(timed)
    return heard, lambda: (
        jax.monitoring.unregister_event_listener(event),
        jax.monitoring.unregister_event_duration_listener(timed),
    )


@pytest.mark.parametrize("recompile", [True, False], ids=["as a user's command", "MAGDESIGN_NO_RECOMPILE"])
def test_after_an_upgrade_a_program_in_the_compilation_cache_is_kept_and_then_loaded(
    kept, fresh_compilation_cache, monkeypatch, recompile
):
    """An upgrade of magdesign (new versions(): every entry of ours misses) leaves JAX's
    compilation cache holding the same program. The executable JAX reads from it serializes
    without its kernels (its entry would fail when run), so the program is compiled once
    more to be kept, and the run after loads it: no trace, no compile, no cache read. With
    MAGDESIGN_NO_RECOMPILE (the tests' choice), what JAX read is run as it is, and not kept."""
    from magdesign._cache import use_compilation_cache

    monkeypatch.setenv("MAGDESIGN_NO_RECOMPILE", "" if recompile else "1")
    _export.enable(kept)
    use_compilation_cache()
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    x, x3 = np.array([0.5, 1.0]), np.array([0.25, 0.5, 2.0])
    expected = np.cumsum(np.sin(x))  # independent: numpy

    def run():  # one command's run in a new process: its events
        _new_process()
        heard, stop = _events()
        try:
            program = _export.jit(lambda x: jnp.cumsum(jnp.sin(x)), "toy-cached", "cumsum sin(x)")
            np.testing.assert_allclose(program(x), expected, rtol=1e-15)
            # and through lower: compiled for a shape alone (another entry), as a sweep does
            compiled = program.lower(jax.ShapeDtypeStruct((3,), jnp.float64)).compile()
            np.testing.assert_allclose(compiled(x3), np.cumsum(np.sin(x3)), rtol=1e-15)
        finally:
            stop()
        return {name: heard.count(f"/jax/{name}") for name in ("compilation_cache/cache_hits", *COMPILE_STAGES)}

    first = run()  # JAX's cache empty: the two programs compiled, written to JAX's cache, kept
    assert first["compilation_cache/cache_hits"] == 0 and first["core/compile/backend_compile_duration"] == 2
    shutil.rmtree(kept)  # the upgrade: our entries miss
    second = run()
    third = run()
    assert second["compilation_cache/cache_hits"] == 2  # read from JAX's cache (a compile event too) ...
    if recompile:
        # the kept executables run (the assertions in run), and nothing is made
        assert all(count == 0 for count in third.values()), third
        assert second["core/compile/backend_compile_duration"] == 4  # ... and compiled again, to be kept
    else:  # such an executable serializes without its kernels: it is never kept
        assert not list(kept.glob("toy-cached-*.executable"))
        for run_after in (second, third):  # each reads both from JAX's cache again, and compiles nothing
            assert run_after["compilation_cache/cache_hits"] == run_after["core/compile/backend_compile_duration"] == 2


# JAX's events of making a program: tracing, lowering, compiling (one each per program).
COMPILE_STAGES = (
    "core/compile/jaxpr_trace_duration",
    "core/compile/jaxpr_to_mlir_module_duration",
    "core/compile/backend_compile_duration",
)


def test_a_new_process_calls_the_kept_executable_without_compiling(tmp_path):
    # independent: the eigenvalues of tridiag(1, 2, 1) are 2 + 2 cos(k pi / 4), k = 1, 2, 3
    expected = 3.0 * np.sort(2.0 + 2.0 * np.cos(np.arange(1, 4) * np.pi / 4))
    first = _run_new_process(tmp_path, MAGDESIGN_NO_EXPORT="")
    assert first["compiled"] >= 1 and len(list(tmp_path.glob("toy-eig-*.executable"))) == 1
    second = _run_new_process(tmp_path, MAGDESIGN_NO_EXPORT="")
    assert second["compiled"] == 0  # read back, its LAPACK call set up without lowering it
    plain = _run_new_process(tmp_path / "unused", MAGDESIGN_NO_EXPORT="1")
    assert not (tmp_path / "unused").exists()
    for answer in (first, second, plain):
        np.testing.assert_allclose(answer["value"], expected, rtol=1e-12)
        np.testing.assert_allclose(answer["batch"], expected, rtol=1e-12)
    np.testing.assert_allclose(second["value"], plain["value"], rtol=1e-12)


def _toy_executable(kept):
    """A kept executable of 2 sin(x), its value and its entry's path."""
    _new_process()
    program = _export.jit(lambda x: 2.0 * jnp.sin(x), "toy", "2 sin(x)")
    value = program(jnp.asarray([0.5, 1.0]))
    return value, kept / sorted(path.name for path in kept.glob("toy-*.executable"))[0]


@pytest.mark.parametrize("damage", ["garbage", "cut short", "other versions", "other structure"])
def test_a_damaged_or_stale_executable_is_a_miss(kept, damage, fresh_compilation_cache):
    expected = 2.0 * np.sin([0.5, 1.0])  # independent: numpy
    _, path = _toy_executable(kept)
    entry = pickle.loads(path.read_bytes())
    # the place holds an executable of another program (x times 100) that a reader must not run
    wrong = jax.jit(lambda x: 100.0 * x).lower(jnp.asarray([0.5, 1.0])).compile()
    wrong_bytes = jax.experimental.serialize_executable.serialize(wrong)[0]
    if damage == "garbage":
        path.write_bytes(b"not an entry")
    elif damage == "cut short":
        path.write_bytes(pickle.dumps({**entry, "executable": entry["executable"][: len(entry["executable"]) // 2]}))
    else:
        old = _export.versions() if damage == "other versions" else "2 sin(x)"
        stale = {**entry, "text": entry["text"].replace(old, "jax 0.0.1, format 0"), "executable": wrong_bytes}
        path.write_bytes(pickle.dumps(stale))
    value, again = _toy_executable(kept)
    np.testing.assert_allclose(value, expected, rtol=1e-15)
    assert again == path and pickle.loads(path.read_bytes())["text"] == entry["text"]  # made again


@pytest.mark.parametrize("damage", ["garbage", "other versions", "other structure"])
def test_a_damaged_or_stale_entry_is_ignored_and_made_again(kept, damage):
    expected = 2.0 * np.sin([0.5, 1.0])  # independent: numpy
    value, path = _toy(kept)
    np.testing.assert_allclose(value, expected, rtol=1e-15)
    entry = pickle.loads(path.read_bytes())
    # the entry's place holds a wrong program (x times 100) that a reader must not run
    wrong = jax.export.export(jax.jit(lambda x: [100.0 * x]))(jax.ShapeDtypeStruct((2,), jnp.float64))
    if damage == "garbage":
        path.write_bytes(b"not an entry")
    else:
        old = _export.versions() if damage == "other versions" else "2 sin(x)"
        new = "jax 0.0.1, jaxlib 0.0.1, magdesign 0.0.1 0000, format 0" if damage == "other versions" else "x"
        stale = {**entry, "text": entry["text"].replace(old, new), "exported": bytes(wrong.serialize())}
        path.write_bytes(pickle.dumps(stale))
    for executable in kept.glob("toy-*.executable"):
        executable.unlink()  # the exported entry is read where no kept executable answers
    value, again = _toy(kept)
    np.testing.assert_allclose(value, expected, rtol=1e-15)
    assert again == path and pickle.loads(path.read_bytes())["text"] == entry["text"]


def test_new_versions_key_a_new_entry(kept, monkeypatch):
    _toy(kept)
    monkeypatch.setattr(_export, "versions", lambda: "jax 99, jaxlib 99, magdesign 99 ffff, format 99")
    _toy(kept)
    assert len(_entries(kept, "toy")) == 2


def test_a_batch_entry_serves_every_batch_length(kept):
    program = _export.jit(lambda a, x: a * x**2, "toy-batch", "a x^2", batched=(1,))
    for count in (3, 5):
        x = np.linspace(0.0, 1.0, count)
        np.testing.assert_allclose(program(jnp.asarray(2.0), jnp.asarray(x)), 2.0 * x**2, rtol=1e-15)
    assert len(_entries(kept, "toy-batch")) == 1


def test_turned_off_by_the_environment(tmp_path, monkeypatch):
    saved = _export.directory()
    try:
        monkeypatch.setenv("MAGDESIGN_NO_EXPORT", "1")
        _export.enable(tmp_path)
        assert _export.directory() is None
        _new_process()
        program = _export.jit(lambda x: 2.0 * jnp.sin(x), "toy", "2 sin(x)")
        np.testing.assert_allclose(program(jnp.asarray([0.5])), 2.0 * np.sin([0.5]), rtol=1e-15)
        np.testing.assert_allclose(program.lower(jnp.asarray([0.5])).compile()(jnp.asarray([0.5])), 2.0 * np.sin([0.5]))
        assert list(tmp_path.iterdir()) == []  # neither an exported program nor an executable
        monkeypatch.setenv("MAGDESIGN_NO_EXPORT", "0")
        _export.enable(tmp_path)
        assert _export.directory() == tmp_path
    finally:
        _export.enable(saved)


@pytest.fixture
def fresh_compilation_cache(tmp_path, monkeypatch):
    """The command's compilation cache in a fresh folder: an executable is kept only where
    this process compiled it, not where JAX read it from the tests' shared cache."""
    monkeypatch.setenv("MAGDESIGN_CACHE_DIR", str(tmp_path / "compiled"))
    saved = jax.config.jax_compilation_cache_dir, jax.config.jax_persistent_cache_min_compile_time_secs
    jax.config.update("jax_compilation_cache_dir", str(tmp_path / "compiled"))
    compilation_cache.reset_cache()
    yield
    jax.config.update("jax_compilation_cache_dir", saved[0])
    jax.config.update("jax_persistent_cache_min_compile_time_secs", saved[1])
    compilation_cache.reset_cache()


@pytest.mark.slow
def test_the_command_keeps_its_programs_and_answers_the_same_from_them(
    tmp_path, monkeypatch, capsys, fresh_compilation_cache
):
    monkeypatch.delenv("MAGDESIGN_NO_EXPORT", raising=False)
    monkeypatch.setattr(cli, "export_directory", lambda directory: tmp_path / "exported")
    answers = []
    for _ in range(2):
        _new_process()
        assert cli.main(["solve", "--fidelity", "reissner", "--json", "--quiet"]) == 0
        answers.append(json.loads(capsys.readouterr().out))
    assert _entries(tmp_path / "exported", "solve") and _entries(tmp_path / "exported", "outputs")
    assert list((tmp_path / "exported").glob("solve-*.executable"))
    assert list((tmp_path / "exported").glob("outputs-*.executable"))
    assert answers[0]["parameters"] == answers[1]["parameters"]
    assert answers[0]["estimates"] == answers[1]["estimates"]
    monkeypatch.setenv("MAGDESIGN_NO_EXPORT", "1")  # the un-kept path: traced and compiled as usual
    _new_process()
    assert cli.main(["solve", "--fidelity", "reissner", "--json", "--quiet"]) == 0
    plain = json.loads(capsys.readouterr().out)
    for name, value in plain["parameters"].items():
        np.testing.assert_allclose(answers[1]["parameters"][name], value, rtol=1e-12)
    assert _export.directory() is None or _export.directory() != tmp_path / "exported"  # only for the command
