"""The Python API's entry points: the subpackages after a plain ``import magdesign``, and a
design model's return checked with an error that names the output and the rule."""

import subprocess
import sys

import jax.numpy as jnp
import pytest

from magdesign.design import Limit, Problem, Target, Variable, solve


@pytest.mark.slow
def test_the_subpackages_load_after_a_plain_import():
    """As the README writes it: ``import magdesign`` then ``magdesign.scene.to_magpylib``;
    magpylib itself (an optional extra) still loads only when the function is called."""
    code = (
        "import sys, magdesign; magdesign.scene.to_magpylib; magdesign.design.Problem; print('magpylib' in sys.modules)"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "False"
    missing = subprocess.run(
        [sys.executable, "-c", "import magdesign; magdesign.nothing"], capture_output=True, text=True, timeout=300
    )
    assert "module 'magdesign' has no attribute 'nothing'" in missing.stderr


@pytest.mark.slow
def test_importing_every_module_starts_no_jax_backend():
    """JAX's device count can be set only before its backend starts (the CLI's --devices
    sets it after importing the package): no module may compute with JAX on import."""
    code = (
        "import pkgutil, importlib, jax, magdesign\n"
        "for m in pkgutil.walk_packages(magdesign.__path__, 'magdesign.'):\n"
        "    if m.name != 'magdesign.__main__': importlib.import_module(m.name)\n"
        "jax.config.update('jax_num_cpu_devices', 2)\n"
        "print(jax.device_count())"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip() == "2"


@pytest.mark.parametrize(
    ("model", "message"),
    [
        (
            lambda p: {"compliance": jnp.stack([p["x"], p["x"], p["x"]])},
            r"compliance: the model must return a dict of scalar outputs; 'compliance' has shape \(3,\)",
        ),
        (lambda p: (p["x"],), r"model: the model must return a dict of scalar outputs .*got a tuple"),
        (lambda p: 2.0 * p["x"], r"model: the model must return a dict of scalar outputs .*got an array of shape \(\)"),
        (lambda p: {"field": p["x"]}, r"compliance: not an output of the model \(outputs: \['field'\]\)"),
        (lambda p: {"compliance": "a"}, r"compliance: the model must return real scalar outputs .*is a str"),
        (lambda p: {"compliance": p["x"] * 1j}, r"compliance: .*real scalar outputs .*is of dtype complex128"),
    ],
    ids=["vector output", "tuple", "bare array", "missing output", "string", "complex"],
)
def test_a_model_that_does_not_return_a_dict_of_scalars_is_named(model, message):
    problem = Problem(model, [Variable("x", 0.0, 1.0)], targets=[Target("compliance", 0.5)])
    with pytest.raises(ValueError, match=message):
        solve(problem)


def test_a_vector_output_read_by_a_limit_is_named():
    def model(p):
        return {"field": p["x"] ** 2, "gap": jnp.array([p["x"], 1.0 - p["x"]])}

    problem = Problem(
        model, [Variable("x", 0.0, 1.0)], targets=[Target("field", 0.25)], limits=[Limit("gap", lower=0.0, scale=1.0)]
    )
    with pytest.raises(ValueError, match=r"gap: .*'gap' has shape \(2,\)"):
        solve(problem)
