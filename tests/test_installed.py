"""The package as a user installs it: the wheel built from this tree, installed with its
dependencies into a fresh virtual environment, runs from a folder outside the source tree,
where no import can reach the checkout's magdesign/.

The dependencies come from the package index, installed by uv where it is beside this
Python or on PATH (``make test`` bootstraps it into .venv; its cache then holds them all),
else by pip, as ``make test`` does to build .venv. One test, so that a parallel run builds
and installs once.
"""

import json
import os
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
# The wheel's inputs, copied so that the build's own folders (build/, *.egg-info) stay out of
# the checkout.
BUILD_INPUTS = ("pyproject.toml", "README.md", "LICENSE", "magdesign")
STUDY = "spin_valve_matrix"  # the cheapest study in --quick mode


def _checked(command, cwd=None, env=None):
    """Run ``command``; its completed process, after checking that its exit code is 0."""
    result = subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True, timeout=900)
    assert result.returncode == 0, f"{' '.join(map(str, command))} exited {result.returncode}:\n{result.stderr}"
    return result


def _uv():
    """uv beside this Python (``make test`` bootstraps it there) or on PATH, else None."""
    beside = Path(sys.executable).parent / "uv"
    return str(beside) if beside.is_file() else shutil.which("uv")


@pytest.mark.slow  # builds the wheel and installs it with jaxlib in a new environment: about a minute
def test_the_installed_wheel_runs_outside_the_source_tree(tmp_path):
    source = tmp_path / "source"
    source.mkdir()
    for name in BUILD_INPUTS:
        if (ROOT / name).is_dir():
            shutil.copytree(ROOT / name, source / name, ignore=shutil.ignore_patterns("__pycache__"))
        else:
            shutil.copy2(ROOT / name, source / name)
    pip = ["-m", "pip", "--disable-pip-version-check", "--quiet"]
    _checked([sys.executable, *pip, "wheel", "--no-deps", "--wheel-dir", tmp_path / "dist", source])
    (wheel,) = (tmp_path / "dist").glob("magdesign-*.whl")
    _checked([sys.executable, "-m", "venv", tmp_path / "env"])
    bin_ = tmp_path / "env" / "bin"
    run = tmp_path / "run"  # outside the source tree
    run.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    # MAGDESIGN_CACHE_DIR stays the tests' compile cache (tests/conftest.py): the same jax
    # compiles the same programs, so the commands load what the other tests compiled.
    env["PATH"] = f"{bin_}{os.pathsep}{env.get('PATH', '')}"

    def command(*args):
        return _checked([bin_ / args[0], *args[1:]], cwd=run, env=env).stdout

    try:
        uv = _uv()
        if uv is None:
            command("python", *pip, "install", wheel)
        else:
            _checked([uv, "pip", "install", "--quiet", "--python", bin_ / "python", wheel], cwd=run, env=env)
        where, version = command("python", "-c", "import magdesign as m; print(m.__file__, m.__version__)").split()
        assert Path(where).is_relative_to(tmp_path / "env")  # the environment's copy, not the checkout's
        assert version == tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]

        solved = json.loads(command("magdesign", "solve", "--json", "--fidelity", "reissner"))
        assert solved["status"] == "successful"
        assert set(solved["parameters"]) == {"geometry.gap", "mechanics.thickness"}

        simulated = json.loads(command("magdesign", "simulate", ROOT / "examples" / "dome_hall.toml", "--json"))
        assert all(simulated["converged"])

        table = command("magdesign", "accuracy", "--quick").splitlines()
        assert any(line.split()[:4] == ["cylinder", "field", "exact", "0.00e+00"] for line in table), table

        out = run / STUDY  # the study imports its _report from beside it, and magdesign from the environment
        printed = command("python", ROOT / "studies" / f"{STUDY}.py", "--quick", "--out", out)
        assert printed.strip().endswith(str(out / "report.md"))
        assert json.loads((out / "results.json").read_text())["quick"] is True
    finally:
        shutil.rmtree(tmp_path / "env", ignore_errors=True)  # 0.7 GB, mostly jaxlib


def test_no_module_reaches_outside_the_package():
    """A wheel holds magdesign/ alone: a module that finds a file through its own path's
    parents (examples/, studies/ beside the package in a checkout) fails when installed."""
    for path in (ROOT / "magdesign").rglob("*.py"):
        text = path.read_text()
        assert ".parents[" not in text and ".parent.parent" not in text, path
