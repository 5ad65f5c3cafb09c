"""Run a study script's ``main`` in quick mode and read back its results."""

import importlib.util
import json
import pathlib
import sys

STUDIES = pathlib.Path(__file__).resolve().parents[2] / "studies"


def run_quick(name: str, out: pathlib.Path) -> dict:
    """``python studies/<name>.py --quick --out <out>``, in this process; returns its
    results.json after checking that report.md opens with the published comparison."""
    if str(STUDIES) not in sys.path:
        sys.path.insert(0, str(STUDIES))
    spec = importlib.util.spec_from_file_location(f"study_{name}", STUDIES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    module.main(["--quick", "--out", str(out)])
    report = (out / "report.md").read_text()
    assert "| quantity | published | source | magdesign | difference | why |" in report
    for figure in json.loads((out / "results.json").read_text()).get("figures", []):
        assert (out / figure).is_file()
    return json.loads((out / "results.json").read_text())
