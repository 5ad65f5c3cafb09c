"""The fewest chips: a skin's design solved over candidate chip grids, the smallest that
succeeds.

A chip count is no design variable (the solver moves continuous parameters), so
:func:`fewest_chips` solves the spec's design once per candidate ``sensor.grid`` ([rows,
columns], each at the spec's ``sensor.pitch`` or the pitch the design varies), in order of
chip count, and stops at the first whose solve is successful. Each candidate keeps its
solver's status; a grid the spec refuses (fewer chips than a contact's five unknowns need,
:data:`~magdesign.spec.skin.SKIN_MIN_CHIPS`, or chips off the skin) keeps the refusal's
message.
"""

import copy
import dataclasses
import warnings
from collections.abc import Callable, Sequence

from magdesign.design.report import DesignResult
from magdesign.design.solve import solve
from magdesign.spec.design import grid_candidate, problem_from_spec
from magdesign.spec.tolerance import tolerance_problem_from_spec
from magdesign.units import SpecError


@dataclasses.dataclass(frozen=True)
class GridTrial:
    """One candidate grid and what became of it.

    Attributes:
        grid: the candidate's ``sensor.grid``, (rows, columns).
        chips: its chip count, rows x columns.
        status: the solver's status ("successful", "infeasible_target", ...), or "refused"
            where the spec with this grid is refused (``reason`` says why).
        result: the solve's :class:`~magdesign.design.report.DesignResult`, None where refused.
        reason: the refusal's one-line message, None where solved.
    """

    grid: tuple[int, int]
    chips: int
    status: str
    result: DesignResult | None = None
    reason: str | None = None


@dataclasses.dataclass(frozen=True)
class FewestChips:
    """The candidates tried, in order of chip count, up to the first that succeeds.

    Attributes:
        trials: each candidate tried (:class:`GridTrial`).
    """

    trials: tuple[GridTrial, ...]

    @property
    def best(self) -> GridTrial | None:
        """The trial with the fewest chips whose solve is successful, or None."""
        return next((trial for trial in self.trials if trial.status == "successful"), None)

    @property
    def status(self) -> str:
        """ "successful" where a candidate succeeds, else "no_grid_succeeded"."""
        return "successful" if self.best is not None else "no_grid_succeeded"

    def table(self) -> str:
        """A readable table of the trials: each grid, its chips, its status, and the targets
        and limits its answer does not meet with its solve's time, or the refusal."""
        lines = [f"  {'sensor.grid':<13}{'chips':<7}{'status':<20}why"]
        for trial in self.trials:
            result = trial.result
            if result is None:
                why = trial.reason
            else:
                missed = f"not met: {', '.join(result.violated)}; " if result.violated else ""
                why = f"{missed}solved in {result.seconds:.3g} s"
            grid = f"[{trial.grid[0]}, {trial.grid[1]}]"
            lines.append(f"  {grid:<13}{trial.chips:<7}{trial.status:<20}{why}".rstrip())
        return "\n".join(lines)

    def to_json(self) -> dict:
        """The search as JSON: its status, the design's grid and chip count (None where no
        grid succeeds), and every trial: its grid, chips, status and refusal, and its solve's
        :meth:`~magdesign.design.report.DesignResult.to_json` where it was solved."""
        best = self.best
        return {
            "status": self.status,
            "grid": None if best is None else list(best.grid),
            "chips": None if best is None else best.chips,
            "trials": [
                {
                    **({} if trial.result is None else trial.result.to_json()),
                    "grid": list(trial.grid),
                    "chips": trial.chips,
                    "status": trial.status,
                    "reason": trial.reason,
                }
                for trial in self.trials
            ],
        }


def fewest_chips(
    spec: dict,
    grids: Sequence[Sequence[int]],
    *,
    key: str = "grids",
    before: Callable[[tuple[int, int]], None] | None = None,
    **options,
) -> FewestChips:
    """Solve a skin's design (``spec``, its chips on ``sensor.grid`` at ``sensor.pitch``) for
    each candidate grid in ``grids`` ([rows, columns] each), fewest chips first (candidates
    of one count in the given order), until one is successful.

    Args:
        spec: a skin's design spec (the dict of a TOML file), with ``sensor.grid``.
        grids: the candidate grids, [rows, columns] each.
        key: the name a bad candidate's error gives it (``key[i]``): "design.grids" where
            they come from the spec.
        before: called with each candidate (rows, columns) before it is tried (a progress line).
        options: passed to :func:`magdesign.design.solve` (rtol, atol, max_steps, solver).

    Returns:
        :class:`FewestChips`: every candidate tried with its status; ``best`` the first
        successful one (None if none is), ``status`` "successful" or "no_grid_succeeded".
        A SpecError where the spec places no chips on a grid, a candidate is not [rows,
        columns] or the spec has an error of its own (its [design.tolerances] included, read
        as the tolerance command reads it); a candidate grid the spec refuses
        (its error names sensor.grid) is a trial with status "refused".
    """
    sensor = spec.get("sensor", {})
    if "grid" not in sensor or "chips" in sensor:
        raise SpecError("sensor.grid: fewest_chips varies the chips' grid; place the chips by sensor.grid and pitch")
    candidates = sorted(
        (grid_candidate(candidate, f"{key}[{i}]") for i, candidate in enumerate(grids)), key=lambda g: g[0] * g[1]
    )
    if not candidates:
        raise SpecError(f"{key}: expected at least one candidate [rows, columns]")
    trials = []
    for grid in candidates:
        if before is not None:
            before(grid)
        trial_spec = copy.deepcopy(spec)
        trial_spec["sensor"]["grid"] = list(grid)
        trial_spec.get("design", {}).pop("grids", None)  # a trial is a design at its grid (and --write writes it so)
        try:
            problem, scene = problem_from_spec(trial_spec)
        except SpecError as error:
            if not str(error).startswith("sensor.grid"):  # the spec's own error, whatever the grid
                raise
            trials.append(GridTrial(grid, grid[0] * grid[1], "refused", reason=str(error)))
            continue
        if "tolerances" in trial_spec.get("design", {}) and not any(t.result is not None for t in trials):
            # read by the tolerance command: refused here as there, before the first solve
            with warnings.catch_warnings():  # the spec's warnings are said by problem_from_spec
                warnings.simplefilter("ignore")
                tolerance_problem_from_spec(trial_spec, built=(problem, scene))
        result = solve(problem, **options)
        trials.append(GridTrial(grid, grid[0] * grid[1], str(result.status), result=result))
        if trials[-1].status == "successful":
            break
    return FewestChips(tuple(trials))
