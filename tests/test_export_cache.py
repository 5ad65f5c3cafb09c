"""The exported programs kept on disk (magdesign._export): one entry per structure, the
spec's numbers arguments of it, damaged or stale entries made again, a switch to turn it off."""

import copy
import json
import pickle

import jax
import jax.numpy as jnp
import numpy as np
import pytest

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


def _new_process():
    """Forget every program this process traced or read, as a new process starts."""
    jax.clear_caches()
    _compiled.cache_clear()
    _export._KEPT.clear()


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
        monkeypatch.setenv("MAGDESIGN_NO_EXPORT", "0")
        _export.enable(tmp_path)
        assert _export.directory() == tmp_path
    finally:
        _export.enable(saved)


@pytest.mark.slow
def test_the_command_keeps_its_programs_and_answers_the_same_from_them(tmp_path, monkeypatch, capsys):
    monkeypatch.delenv("MAGDESIGN_NO_EXPORT", raising=False)
    monkeypatch.setattr(cli, "export_directory", lambda directory: tmp_path / "exported")
    answers = []
    for _ in range(2):
        _new_process()
        assert cli.main(["solve", "--fidelity", "reissner", "--json", "--quiet"]) == 0
        answers.append(json.loads(capsys.readouterr().out))
    assert _entries(tmp_path / "exported", "solve") and _entries(tmp_path / "exported", "outputs")
    assert answers[0]["parameters"] == answers[1]["parameters"]
    assert answers[0]["estimates"] == answers[1]["estimates"]
    assert _export.directory() is None or _export.directory() != tmp_path / "exported"  # only for the command
