"""A command's second run compiles and traces nothing: its spec stage makes its arrays
without programs (magdesign._tracing.on_device), its solver and model programs are read
from the kept executables (magdesign._export), and what it would learn from a trace
(whether a model runs loops of its own) is kept beside them."""

import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from magdesign._tracing import on_device, random_key, strongly_typed

DEFAULT_SPEC = str(Path(__file__).resolve().parent.parent / "magdesign" / "design" / "default.toml")

# Prints {"compiled": n, "traced": n} after running argv[1] in a new process: a command
# (the rest of argv its arguments), "spec" (the spec stage of the default design and
# the host-side checks a command makes of it) or "scenes" (the scenes of the spec files
# that follow, with their checks).
_COUNTED = textwrap.dedent(
    """
    import contextlib, io, json, sys
    import jax
    events = []
    jax.monitoring.register_event_duration_secs_listener(lambda event, seconds, **kwargs: events.append(event))
    if sys.argv[1] == "spec":
        import numpy as np
        from magdesign._tracing import random_key
        from magdesign.mechanics._ladder import bound
        from magdesign.scene import with_parameters
        from magdesign.spec.design import default_spec, problem_from_spec
        problem, scene = problem_from_spec(default_spec(), fidelity="reissner")
        with_parameters(scene, {v.name: float(v.start) for v in problem.variables})
        random_key(0)
        float(bound(1.0, 1.01, True))
    elif sys.argv[1] == "scenes":  # the scenes of the specs argv[2:] and the checks of their loads
        import warnings
        from magdesign.spec.design import load_spec
        from magdesign.spec.scene import scene_from_spec
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the examples' own plausibility warnings
            for path in sys.argv[2:]:
                scene_from_spec(load_spec(path))
    else:
        from magdesign import cli
        with contextlib.redirect_stdout(io.StringIO()):
            cli.main(sys.argv[1:])
    count = lambda name: sum(event == f"/jax/core/compile/{name}_duration" for event in events)
    print(json.dumps({"compiled": count("backend_compile"), "traced": count("jaxpr_trace")}))
    """
)


def _counted(*arguments, cache=None):
    environment = {**os.environ, "MAGDESIGN_NO_EXPORT": "", "MAGDESIGN_NO_RECOMPILE": ""}  # as a user's command
    if cache is not None:
        environment["MAGDESIGN_CACHE_DIR"] = str(cache)
    done = subprocess.run(
        [sys.executable, "-c", _COUNTED, *arguments], capture_output=True, text=True, check=True, env=environment
    )
    return json.loads(done.stdout.splitlines()[-1])


def test_the_spec_stage_compiles_and_traces_nothing_in_a_new_process():
    assert _counted("spec") == {"compiled": 0, "traced": 0}


def test_a_skins_spec_stage_compiles_and_traces_nothing_in_a_new_process(tmp_path):
    """A skin's checks (its contact patch and strain, the outputs' map, the chips) compute
    with numpy, and its arrays are made without programs; a neo_hookean layer's too (its
    press is solved when the scene runs, not when it is built)."""
    examples = Path(__file__).resolve().parent.parent / "examples"
    skins = [str(examples / f"{name}.toml") for name in ("skin", "skin_pattern", "eflesh")]
    text = (examples / "skin.toml").read_text()
    neo_hookean = text.replace("poisson_ratio = 0.49", 'material = "neo_hookean"\nbulk_modulus = "10 MPa"')
    neo_hookean = neo_hookean.replace("direction = [0, 0, 1]", 'direction = [0, 0, 1]\nfield = "cells"')
    assert neo_hookean.count("neo_hookean") == 1 and neo_hookean.count('"cells"') == 1
    (tmp_path / "neo_hookean.toml").write_text(neo_hookean)
    skins.append(str(tmp_path / "neo_hookean.toml"))
    assert _counted("scenes", *skins) == {"compiled": 0, "traced": 0}


@pytest.mark.slow
@pytest.mark.parametrize(
    "command, upgrade",
    [
        (["sweep", DEFAULT_SPEC, "--over", "compliance=0.3mm/N:0.34mm/N:3", "--fidelity", "reissner"], False),
        (["simulate", DEFAULT_SPEC], False),
        (["solve", "--fidelity", "reissner"], True),
    ],
    ids=["sweep", "simulate", "solve"],
)
def test_a_second_run_of_a_command_compiles_and_traces_nothing(tmp_path, command, upgrade):
    arguments = [*command, "--json", "--quiet"]
    first = _counted(*arguments, cache=tmp_path)
    assert first["compiled"] > 0  # a fresh cache: the first run compiles the programs it keeps
    assert _counted(*arguments, cache=tmp_path) == {"compiled": 0, "traced": 0}
    if upgrade:
        # An upgrade of magdesign makes every entry of ours a miss (new versions()), while
        # JAX's compilation cache holds the same programs: the run after it reads them from
        # there and compiles them once more to keep them (magdesign._export._Program._keep),
        # and the run after that compiles and traces nothing again.
        shutil.rmtree(tmp_path / "exported")
        assert _counted(*arguments, cache=tmp_path)["compiled"] > 0
        assert _counted(*arguments, cache=tmp_path) == {"compiled": 0, "traced": 0}


def test_random_key_is_jax_random_key():
    for seed in (0, 1, 7, 2**32 + 5, 2**62 + 3):
        made = random_key(seed)
        assert jax.random.key_impl(made) == jax.random.key_impl(jax.random.key(seed))
        np.testing.assert_array_equal(jax.random.key_data(made), jax.random.key_data(jax.random.key(seed)))
    np.testing.assert_array_equal(jax.random.key_data(random_key(-3)), jax.random.key_data(jax.random.key(-3)))


def test_on_device_and_strongly_typed_make_strong_arrays_of_the_same_values():
    for value in (0.32e-3, [1.0, 2.5, -3.0], np.array([[1.0, 2.0]]), 3):
        made = on_device(value)
        assert isinstance(made, jax.Array) and not made.weak_type
        assert made.dtype == np.asarray(value).dtype
        np.testing.assert_array_equal(made, np.asarray(value))
    weak = jnp.asarray(1.25)
    assert weak.weak_type and on_device(weak) is weak  # a jax array is left as it is
    strong = strongly_typed(weak)
    assert not strong.weak_type and strong.dtype == jnp.float64 and float(strong) == 1.25
    assert strongly_typed(strong) is strong
    from_numpy = strongly_typed(np.array([0.5, 2.0]))
    assert isinstance(from_numpy, jax.Array) and not from_numpy.weak_type
    np.testing.assert_array_equal(from_numpy, [0.5, 2.0])


@pytest.mark.parametrize("collecting", [True, False])
def test_importing_magdesign_freezes_what_it_loaded_and_leaves_the_collector_as_it_was(collecting):
    # The package loads JAX with Python's collector off and then freezes what is alive
    # (magdesign/__init__.py): a command's start skips the collections that its imports set
    # off. Asked in a new process, where nothing was imported before.
    script = (
        "import gc, sys\n"
        f"{'' if collecting else 'gc.disable()'}\n"
        "import magdesign.cli\n"
        "print(gc.isenabled(), gc.get_freeze_count(), 'jax' in sys.modules)\n"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True)
    enabled, frozen, jax_loaded = done.stdout.split()
    assert enabled == str(collecting) and jax_loaded == "True"
    # JAX's modules alone are over 100,000 objects (regression value: 168,000 here); a
    # freeze before the imports, or none, leaves a few hundred or 0
    assert int(frozen) > 100_000


def test_a_run_loads_ahead_the_executables_that_its_last_run_read(tmp_path, monkeypatch):
    # Two "runs" of one name in this process, the second as a new process finds the folder:
    # the program's executable is loaded in load_ahead's thread, and the call takes it.
    from magdesign import _export

    program = _export.jit(lambda x, y: {"sum": x + 2.0 * y}, "ahead_test", "x + 2 y")
    x, y = jnp.arange(3.0), jnp.ones(3)
    monkeypatch.setattr(_export, "_state", {"directory": None})
    monkeypatch.setattr(_export, "_AHEAD", {})
    monkeypatch.setattr(_export, "_USED", None)
    _export.enable(tmp_path)
    try:
        _export.load_ahead("run C")
        program(x, y)
        _export.remember_run("run C", succeeded=False)  # a failed run's list may be cut short: not kept
        assert not list(tmp_path.glob("run-*.names"))
        _export.load_ahead("run A")
        first = program(x, y)
        _export.remember_run("run A")
        assert len(list(tmp_path.glob("run-*.names"))) == 1
        _export._LOADED.clear()  # what a new process starts without
        _export.load_ahead("run A")
        (path,) = _export._AHEAD
        assert path.name.startswith("ahead_test-") and path.suffix == ".executable"
        taken = []
        loaded_ahead = _export._loaded_ahead
        monkeypatch.setattr(_export, "_loaded_ahead", lambda *a: taken.append(loaded_ahead(*a)) or taken[-1])
        second = program(x, y)
        assert taken and taken[0] is not None and not _export._AHEAD
        np.testing.assert_array_equal(second["sum"], first["sum"])
        np.testing.assert_array_equal(second["sum"], [2.0, 3.0, 4.0])  # 0..2 + 2
        _export.remember_run("run A")
        _export.load_ahead("run A")  # held by this process already: nothing loaded again
        assert not _export._AHEAD
        _export.remember_run("run A")
        # another run's name loads nothing ahead; an entry loaded ahead for another text is
        # not taken, and the call reads and compiles as usual
        _export.load_ahead("run B")
        assert not _export._AHEAD
        _export.remember_run("run B")
        _export._LOADED.clear()
        _export.load_ahead("run A")
        (path,) = _export._AHEAD
        taken.clear()
        assert _export._loaded_ahead(path, "another text") is None
        np.testing.assert_array_equal(program(x, y)["sum"], [2.0, 3.0, 4.0])
        _export.remember_run("run A")
    finally:
        _export.enable(None)


def test_a_sweep_that_sets_up_its_devices_loads_nothing_ahead(monkeypatch):
    # --devices and jax.distributed must come before JAX starts its backend, which loading
    # ahead would start: such a sweep neither loads ahead nor names its run
    from magdesign._cli_parser import build_parser
    from magdesign.cli import _sets_up_devices

    sweep = ["sweep", DEFAULT_SPEC, "--over", "compliance=0.3mm/N:0.34mm/N:3"]
    monkeypatch.delenv("JAX_COORDINATOR_ADDRESS", raising=False)
    parse = build_parser().parse_args
    assert not _sets_up_devices(parse(sweep)) and not _sets_up_devices(parse(["solve", "--fidelity", "reissner"]))
    assert _sets_up_devices(parse([*sweep, "--devices", "1"]))
    assert _sets_up_devices(parse([*sweep, "--distributed"]))
    assert _sets_up_devices(
        parse([*sweep, "--coordinator", "localhost:1234", "--num-processes", "1", "--process-id", "0"])
    )
    monkeypatch.setenv("JAX_COORDINATOR_ADDRESS", "localhost:1234")
    assert _sets_up_devices(parse(sweep))
