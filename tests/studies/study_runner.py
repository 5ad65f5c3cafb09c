"""Run a study script's ``main`` in quick mode and read back its results."""

import importlib.util
import json
import pathlib
import sys

STUDIES = pathlib.Path(__file__).resolve().parents[2] / "studies"


def load_study(name: str):
    """The module of ``studies/<name>.py``, imported without running it."""
    if str(STUDIES) not in sys.path:
        sys.path.insert(0, str(STUDIES))
    spec = importlib.util.spec_from_file_location(f"study_{name}", STUDIES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def run_quick(name: str, out: pathlib.Path) -> dict:
    """``python studies/<name>.py --quick --out <out>``, in this process; returns its
    results.json after checking that report.md opens with the published comparison."""
    load_study(name).main(["--quick", "--out", str(out)])
    report = (out / "report.md").read_text()
    assert "| quantity | published | source | magdesign | difference | why |" in report
    for figure in json.loads((out / "results.json").read_text()).get("figures", []):
        assert (out / figure).is_file()
    return json.loads((out / "results.json").read_text())


def published_cells(out: pathlib.Path) -> list[str]:
    """The 'published' cells of the report's first table, which must open the report."""
    lines = [
        line
        for line in (out / "report.md").read_text().splitlines()[1:]
        if line.strip() and not line.startswith("*Quick mode")
    ]
    assert lines[0] == "| quantity | published | source | magdesign | difference | why |"
    cells = []
    for line in lines[2:]:
        if not line.startswith("|"):
            break
        cells.append(line.split(" | ")[1])
    return cells


def assert_opens_with(out: pathlib.Path, published: list[str], *, whole_cells: bool = False) -> None:
    """Every value in ``published`` appears in the 'published' column of the report's first
    table (as a whole cell with ``whole_cells``, else within one)."""
    cells = published_cells(out)
    for value in published:
        assert (value in cells) if whole_cells else any(value in cell for cell in cells), value
