"""What every study shares: its command line, its progress lines and its report.

A study writes ``studies/out/<name>/``: ``report.md`` (plain words and tables, opening with
the table published | magdesign | difference | why), the PNG figures it refers to, and
``results.json`` (every number the report prints, in SI, keyed by name). Numbers in the
report come from the study's own computation; published numbers are typed in with their
source.
"""

import argparse
import json
import math
import pathlib
import re
import sys
import time

OUT = pathlib.Path(__file__).resolve().parent / "out"


def arguments(name: str, argv=None, description: str = "", plot: bool = False) -> argparse.Namespace:
    """The command line every study takes: ``--quick`` (small grids, cheapest fidelity,
    for CI) and ``--out DIR`` (default ``studies/out/<name>``); with ``plot``, also
    ``--plot`` (draw the study's figures, which it leaves out otherwise)."""
    parser = argparse.ArgumentParser(prog=f"studies/{name}.py", description=description)
    parser.add_argument("--quick", action="store_true", help="small grids and the cheapest fidelity (CI)")
    parser.add_argument("--out", type=pathlib.Path, default=OUT / name, help="output folder")
    if plot:
        parser.add_argument("--plot", action="store_true", help="draw the figures")
    return parser.parse_args(argv)


_START = time.perf_counter()


def progress(message: str) -> None:
    """One progress line on stderr, with the seconds since the study started."""
    print(f"[{time.perf_counter() - _START:7.1f} s] {message}", file=sys.stderr, flush=True)


def number(value, digits: int = 4) -> str:
    """``value`` with ``digits`` significant digits (a string passes through)."""
    if isinstance(value, str):
        return value
    value = float(value)
    if not math.isfinite(value):
        return str(value)
    return f"{value:.{digits}g}"


# The banner of a quick-mode report, unless the study says what its quick mode does.
QUICK_NOTE = "small grids and the cheapest fidelity; numbers are coarse."


class Report:
    """A study's report, built in order and written once by :meth:`write`. In quick mode it
    opens with a banner, "Quick mode: " and ``quick_note`` (what the study's quick mode
    leaves out; QUICK_NOTE by default)."""

    def __init__(self, name: str, title: str, out: pathlib.Path, quick: bool, quick_note: str = QUICK_NOTE):
        self.name, self.out, self.quick = name, pathlib.Path(out), quick
        self.out.mkdir(parents=True, exist_ok=True)
        self.lines = [f"# {title}", ""]
        if quick:
            self.lines += [f"*Quick mode: {quick_note}*", ""]
        self.results: dict = {"study": name, "quick": quick}
        self.figures: list[str] = []

    def comparison(self, rows) -> None:
        """The report's first table. Each row is a dict with ``quantity``, ``published``
        (text, with its unit), ``source`` (figure, table or page), ``magdesign`` (text),
        ``difference`` (text) and ``why`` (within which tolerance, or the named modelling
        choice that explains it)."""
        self.table(
            ["quantity", "published", "source", "magdesign", "difference", "why"],
            [[r["quantity"], r["published"], r["source"], r["magdesign"], r["difference"], r["why"]] for r in rows],
        )

    def heading(self, text: str, level: int = 2) -> None:
        self.lines += ["#" * level + " " + text, ""]

    def text(self, paragraph: str) -> None:
        self.lines += [paragraph.strip(), ""]

    def table(self, headers, rows) -> None:
        """A markdown table; numbers are written with :func:`number`, a bare ``|`` in a
        cell is escaped."""
        cells = [[re.sub(r"(?<!\\)\|", r"\\|", number(c)) for c in row] for row in rows]
        self.lines.append("| " + " | ".join(headers) + " |")
        self.lines.append("|" + "---|" * len(headers))
        self.lines += ["| " + " | ".join(row) + " |" for row in cells]
        self.lines.append("")

    def figure(self, fig, filename: str, caption: str) -> None:
        """Save a matplotlib figure as ``out/filename`` (PNG) and show it in the report."""
        import matplotlib.pyplot as plt

        fig.savefig(self.out / filename, dpi=110, bbox_inches="tight")
        plt.close(fig)
        self.figures.append(filename)
        self.lines += [f"![{caption}]({filename})", "", f"*{caption}*", ""]

    def result(self, key: str, value) -> None:
        """Record a number (SI) or a small structure in results.json."""
        self.results[key] = _plain(value)

    def write(self) -> pathlib.Path:
        """Write report.md and results.json; print where they are."""
        self.results["seconds"] = round(time.perf_counter() - _START, 2)
        self.results["figures"] = self.figures
        (self.out / "report.md").write_text("\n".join(self.lines))
        (self.out / "results.json").write_text(json.dumps(self.results, indent=2, allow_nan=False) + "\n")
        print(f"{self.name}: {self.out / 'report.md'}")
        return self.out / "report.md"


def _plain(value):
    """JSON-ready: arrays to lists, non-finite floats to None."""
    if hasattr(value, "tolist"):
        value = value.tolist()
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value
