"""Every code block of README.md and docs/*.md runs.

Each page's blocks run in order in a fresh folder (with ``examples/`` linked in, so the pages'
paths resolve):

- ``python``: executed by this interpreter in a subprocess; must exit 0.
- ``toml``: read as a spec by magdesign's own reader (the scene, and the design problem where
  there is a ``[design]`` table). A fragment (no ``magnet.shape``) is read on top of the
  built-in default design. A block whose first line is a comment naming a ``.toml`` file
  (``# quickstart.toml``) is also written to that file for the commands after it.
- ``sh``: each command runs; ``magdesign ...`` (or ``.venv/bin/magdesign ...``) as
  ``python -m magdesign ...``, which must exit 0 (or the code a trailing ``# exit N`` names);
  ``make ...`` is checked with ``make -n``. Any other command is an error: mark its block.
- ``output``: the expected output of the ``python`` or ``sh`` block before it. Each of its
  lines must appear, in order, in that block's standard output (runs of spaces compare as one;
  ``...`` matches anything, for times).
- ``text``: listings (synopses, tables of a dated run); not run.

A block preceded by ``<!-- docs-test: skip (reason) -->`` is not run; the reason is required.
"""

import os
import re
import shlex
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
FENCE = re.compile(
    r"^(?P<skip><!-- docs-test: skip \((?P<reason>[^)]+)\) -->\n)?"
    r"^```(?P<lang>[\w-]*)[^\n]*\n(?P<body>.*?)^```\s*$",
    re.M | re.S,
)
TIMEOUT = 600


def blocks(text):
    """[(language, body, skip reason or None, line number)] of the page's fenced blocks."""
    return [(m["lang"], m["body"], m["reason"], text.count("\n", 0, m.start("lang")) + 1) for m in FENCE.finditer(text)]


def commands(body):
    """The block's shell commands: comments and blank lines dropped, continuations joined."""
    joined = re.sub(r"\\\n\s*", " ", body)
    for line in joined.splitlines():
        words = shlex.split(line, comments=True)
        if words:
            code = re.search(r"#\s*exit (\d+)\s*$", line)
            yield words, int(code[1]) if code else 0


def run_shell(body, cwd, env):
    output = []
    for words, expected in commands(body):
        if words[0] in ("magdesign", ".venv/bin/magdesign"):
            argv, where = [sys.executable, "-m", "magdesign", *words[1:]], cwd
        elif words[0] == "make":
            argv, where = ["make", "-n", *words[1:]], ROOT
        else:
            pytest.fail(f"{words[0]}: not a magdesign or make command; mark its block with a reason to skip it")
        done = subprocess.run(argv, cwd=where, env=env, capture_output=True, text=True, timeout=TIMEOUT)
        assert done.returncode == expected, f"{' '.join(words)}: exit {done.returncode}\n{done.stderr[-3000:]}"
        output.append(done.stdout)
    return "".join(output)


def run_python(body, cwd, env):
    done = subprocess.run(
        [sys.executable, "-c", body], cwd=cwd, env=env, capture_output=True, text=True, timeout=TIMEOUT
    )
    assert done.returncode == 0, f"python block: exit {done.returncode}\n{done.stderr[-3000:]}"
    return done.stdout


def read_spec(body):
    from magdesign.scene import scene_from_spec
    from magdesign.spec.design import default_spec, problem_from_spec

    spec = tomllib.loads(body)
    if "shape" not in spec.get("magnet", {}):  # a fragment: read on top of the default design
        spec = merged(default_spec(), spec)
    if "design" in spec:
        problem_from_spec(spec)
    else:
        scene_from_spec(spec)


def merged(base, extra):
    """``base`` with ``extra``'s keys put in, tables merged key by key."""
    out = dict(base)
    for key, value in extra.items():
        out[key] = merged(out[key], value) if isinstance(value, dict) and isinstance(out.get(key), dict) else value
    return out


def check_output(expected, output):
    """Each expected line in order in ``output``, runs of spaces as one, ``...`` as anything."""
    squash = lambda line: " ".join(line.split())
    lines = [squash(line) for line in output.splitlines()]
    at = 0
    for want in filter(None, map(squash, expected.splitlines())):
        pattern = re.compile(".*".join(map(re.escape, want.split("..."))) + r"\Z")
        while at < len(lines) and not pattern.match(lines[at]):
            at += 1
        assert at < len(lines), f"expected line not in the output (in order): {want!r}\noutput:\n{output}"
        at += 1


def runs_the_library(page):
    """Whether a block of the page runs Python or a magdesign command (each compiles its
    programs in a new process: seconds to a minute a page), not only specs and ``make -n``."""
    return any(
        language == "python" or any(words[0] != "make" for words, _ in commands(body))
        for language, body, skip, _ in blocks(page.read_text())
        if not skip and language in ("python", "sh")
    )


@pytest.mark.parametrize(
    "page",
    [
        pytest.param(
            page, id=page.relative_to(ROOT).as_posix(), marks=pytest.mark.slow if runs_the_library(page) else ()
        )
        for page in PAGES
    ],
)
def test_code_blocks(page, tmp_path):
    text = page.read_text()
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    (tmp_path / "docs").mkdir()  # commands that write a figure into docs/ write it here
    env = dict(os.environ, MPLBACKEND="Agg")
    last = None  # the standard output of the block before, if it ran; "skipped" if it did not
    for language, body, skip, line in blocks(text):
        where = f"{page.name}:{line}"
        if skip or (language == "output" and last == "skipped"):
            last = "skipped"
            continue
        try:
            last = run_block(language, body, last, tmp_path, env)
        except AssertionError as error:
            raise AssertionError(f"{where}: {error}") from None


def run_block(language, body, last, cwd, env):
    """Run one block; its standard output, for an ``output`` block after it (else None)."""
    if language == "output":
        assert last is not None, "an output block follows no python or sh block"
        check_output(body, last)
        return None
    if language == "text":
        return None
    if language == "python":
        return run_python(body, cwd, env)
    if language == "sh":
        return run_shell(body, cwd, env)
    if language == "toml":
        read_spec(body)
        name = body.splitlines()[0].lstrip("# ").strip()
        if body.startswith("#") and name.endswith(".toml") and " " not in name:
            (cwd / name).write_text(body)
        return None
    pytest.fail(f"a ```{language} block: the docs test knows python, toml, sh, output and text blocks")


def test_skips_give_reasons():
    """A skipped block says why, and skips are few; every fence starts its line (an indented
    block would not be found, so would not run)."""
    for page in PAGES:
        text = page.read_text()
        assert not re.search(r"^[ \t]+```", text, re.M), f"{page.name}: an indented fenced block"
        assert len(re.findall(r"^```", text, re.M)) % 2 == 0, f"{page.name}: an unclosed fence"
        marks = re.findall(r"<!-- docs-test: skip[^>]*-->", text)
        assert all(re.fullmatch(r"<!-- docs-test: skip \([^)]+\) -->", mark) for mark in marks), page
        assert len(marks) <= max(2, len(blocks(text)) // 3), f"{page.name}: {len(marks)} blocks skipped"
