"""Worker-seconds of each test module in the fast tier (`make test`) and the slow one, from
the JUnit file of a full run, and the modules that have no fast test.

    .venv/bin/python -m pytest -q -n 2 --dist loadscope --junitxml=run.xml
    .venv/bin/python .ci/test_tiers.py run.xml

A module's fixtures are timed with its first test, so a time moves to the next test of the
module when the first is marked slow. Exits 1 where a module has no fast test.
"""

import subprocess
import sys
import xml.etree.ElementTree as ET
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def fast_ids():
    """The node ids `make test` collects (`-m "not slow"`)."""
    listing = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:xdist", "--collect-only", "-m", "not slow"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    return {line.strip() for line in listing.splitlines() if "::" in line}


def node_id(classname, name):
    """pytest's node id of a JUnit test case: the longest prefix of its dotted class name that
    is a file is the module, the rest its classes."""
    parts = classname.split(".")
    for cut in range(len(parts), 0, -1):
        path = "/".join(parts[:cut]) + ".py"
        if (ROOT / path).is_file():
            return "::".join([path, *parts[cut:], name])
    raise ValueError(f"{classname}: no module of that name")


def main(junit):
    fast = fast_ids()
    seconds = defaultdict(lambda: {True: 0.0, False: 0.0})
    counts = defaultdict(lambda: {True: 0, False: 0})
    for case in ET.parse(junit).iter("testcase"):
        nid = node_id(case.get("classname"), case.get("name"))
        module, tier = nid.split("::")[0], nid in fast
        seconds[module][tier] += float(case.get("time"))
        counts[module][tier] += 1
    print(f"{'module':56} {'fast s':>8} {'tests':>5} {'slow s':>8} {'tests':>5}")
    for module in sorted(seconds, key=lambda m: -sum(seconds[m].values())):
        s, n = seconds[module], counts[module]
        print(f"{module:56} {s[True]:8.1f} {n[True]:5d} {s[False]:8.1f} {n[False]:5d}")
    total = {tier: sum(s[tier] for s in seconds.values()) for tier in (True, False)}
    print(f"{'all':56} {total[True]:8.1f} {'':5} {total[False]:8.1f}")
    missing = sorted(module for module in counts if counts[module][True] == 0)
    for module in missing:
        print(f"no fast test: {module}")
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
