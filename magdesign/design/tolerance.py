"""Tolerance analysis and robust design: a Monte Carlo over a design's own scene.

A design spec states its tolerances in a [design.tolerances] table, read into a
:class:`~magdesign.spec.tolerance.ToleranceProblem` by
:func:`~magdesign.spec.tolerance.tolerance_problem_from_spec` (the table's grammar is
there).

Each sample is the design's scene with its inputs moved: a parameter through
:func:`~magdesign.scene.with_parameters`; placement, tilt and temperature through the scene's
own effects (:class:`~magdesign.scene.effects.Placement`, ``ChipTilt``, ``TemperatureDrift``),
their values moved from the scene's, or the effect added at zero (temperature: with the
``[scene] temperature_coefficient``, default NdFeB's) where the scene does not list it. So
every sample runs the chain :func:`~magdesign.scene.simulate` runs, and
:func:`~magdesign.scene.outputs` reads it. Placement and tilt are drawn for each sensor
independently (chips placed one by one); every component of every input is independent.

The yield is the fraction of samples meeting every target that states a ``tolerance``
(targets without one are shown, not judged) and every limit of the design (its geometry
guards included), with finite outputs and converged mechanics. Sensitivities are first
order: sigma_i |d output / d input_i| at the design (forward mode), set beside the same
read from the samples (the regression slope cov(output, u_i) / var(u_i) times sigma_i, which
for a normal input is the derivative averaged over the distribution).

A robust design (:func:`robust_solve`) solves again with every limit held at k first-order
sigmas, ``output + k sigma <= upper`` and ``output - k sigma >= lower``; targets keep their
nominal values.

A scene whose field is the on-axis closed form (``[magnet] fidelity = "axis"``, exact on the
axis) is analysed with the exact field where a placement tolerance moves its sensors off the
axis: the design solve keeps the cheap form, whose answer is the same.
"""

import math
import time
import warnings

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, PRNGKeyArray
from matplotlib.figure import Figure
from tqdm import tqdm

from magdesign._files import replaced
from magdesign._numerics import ROUNDING_SPREAD, TINY
from magdesign.design.problem import Limit, Problem
from magdesign.design.report import DesignResult, format_quantity
from magdesign.design.solve import solve
from magdesign.scene import AbstractScene, outputs, parameters, with_parameters
from magdesign.spec.sizes import SizeWarning
from magdesign.spec.tolerance import AXES, EFFECT_INPUTS, ToleranceProblem, check_spreads
from magdesign.spec.tolerance import tolerance_problem_from_spec as tolerance_problem_from_spec
from magdesign.units import convert

# Samples per compiled batch: bounds the memory of a run (a few hundred MB for the default scene).
CHUNK = 16384
PERCENTILES = (0.1, 1.0, 50.0, 99.0, 99.9)
# A table leaves out an input whose first-order part is 0 and whose Monte Carlo slope is
# below this many standard errors of a regression slope, std / sqrt(samples): noise.
NOISE_SIGMAS = 3.0
# A robust solve stops when k sigma moves by less than this fraction of each limit's scale,
# or after this many solves.
ROBUST_RTOL = 1e-8
ROBUST_ROUNDS = 20


def perturb(scene: AbstractScene, inputs, sensors: int, u: Float[Array, " d"]) -> AbstractScene:
    """The scene with each toleranced input moved by its size times its unit variates
    ``u`` (D,) (in the order of ``inputs``; traceable, differentiable in ``u``)."""
    nominal = parameters(scene)
    values = {}
    start = 0
    for tolerance in inputs:
        shape = tolerance.components(sensors)
        count = math.prod(shape)
        z = u[start : start + count].reshape(shape)
        start += count
        if tolerance.name in EFFECT_INPUTS:
            cls, field, _, _ = EFFECT_INPUTS[tolerance.name]
            index = next(i for i, effect in enumerate(scene.effects) if isinstance(effect, cls))
            value = getattr(scene.effects[index], field)
            moved = jnp.broadcast_to(value, shape) + tolerance.size * z
            scene = eqx.tree_at(lambda s, i=index, f=field: getattr(s.effects[i], f), scene, moved)
        else:
            width = tolerance.size * jnp.abs(nominal[tolerance.name]) if tolerance.relative else tolerance.size
            values[tolerance.name] = nominal[tolerance.name] + width * z
    return with_parameters(scene, values)


def first_order(tp: ToleranceProblem, scene: AbstractScene) -> tuple[dict, dict]:
    """({output: value}, {output: (D,) sigma_i d output / d u_i}) at ``scene`` (u = 0):
    the outputs and each variate's first-order part of their spread (SI; forward mode)."""
    unit_std = jnp.asarray(tp.unit_std)

    def values(u):
        result = outputs(perturb(scene, tp.inputs, tp.sensors, u), tp.loads)
        return result, result

    jacobian, nominal = jax.jacfwd(values, has_aux=True)(jnp.zeros(unit_std.shape[0]))
    return nominal, {name: row * unit_std for name, row in jacobian.items()}


@eqx.filter_jit
def _first_order(tp, scene):
    return first_order(tp, scene)


@eqx.filter_jit
def _chunk(tp: ToleranceProblem, scene: AbstractScene, key: PRNGKeyArray, count: int, names: tuple[str, ...]):
    """(u (count, D), {name: (count,)}): ``count`` samples drawn with ``key`` and their outputs."""
    dimension = len(tp.unit_std)
    normal_key, uniform_key = jax.random.split(key)
    u = jax.random.normal(normal_key, (count, dimension))
    if tp.uniform.any():
        u = jnp.where(tp.uniform, jax.random.uniform(uniform_key, (count, dimension), minval=-1.0, maxval=1.0), u)
    run = jax.vmap(lambda ui: outputs(perturb(scene, tp.inputs, tp.sensors, ui), tp.loads))
    result = run(u)
    return u, {name: result[name] for name in names}


class ToleranceResult(eqx.Module):
    """A Monte Carlo of one design (SI values, Python floats and numpy arrays).

    Attributes:
        parameters: {variable: value} of the design analysed.
        samples, seed: the run's size and its PRNG seed; seconds: its wall time.
        yield_fraction: the fraction of samples meeting every judged target and every
            limit (with finite outputs and converged mechanics); yield_stderr its binomial
            standard error sqrt(y (1 - y) / samples).
        outputs: {output: {"unit", "nominal", "mean", "std", "std_first_order",
            "percentiles": {p: value}, "bounds": {"upper"/"lower"/"value"/"tolerance": SI},
            "failing": fraction of samples breaking its row, or None when not judged}}.
        sensitivities: {output: {input group: {"first_order": SI, "monte_carlo": SI}}},
            sorted by first-order size, largest first.
        unusable: {"nonfinite": samples with a NaN or inf output, "not_converged": samples
            whose mechanics did not converge}; they count as failing.
        values: {output: (samples,) array}, for pictures.
        units: {output: display unit or None}.
    """

    parameters: dict
    samples: int
    seed: int
    seconds: float
    yield_fraction: float
    yield_stderr: float
    outputs: dict
    sensitivities: dict
    unusable: dict
    values: dict
    units: dict

    def to_json(self) -> dict:
        return {
            "parameters": dict(self.parameters),
            "samples": self.samples,
            "seed": self.seed,
            "seconds": self.seconds,
            "yield": self.yield_fraction,
            "yield_stderr": self.yield_stderr,
            "outputs": self.outputs,
            "sensitivities": self.sensitivities,
            "unusable": dict(self.unusable),
            "units": {name: unit for name, unit in self.units.items() if unit is not None},
        }

    def table(self, top: int = 5) -> str:
        """The outputs' spread, the yield, and the ``top`` inputs that matter most per output."""
        unit = self.units.get
        shown = lambda name, value: format_quantity(value, unit(name))  # noqa: E731
        rows = [["output", "nominal", "mean", "std", "std 1st order", "p0.1", "p99.9", "judged by", "failing"]]
        for name, entry in self.outputs.items():
            bounds = entry["bounds"]
            if "value" in bounds:
                judged = f"±{shown(name, bounds['tolerance'])}" if "tolerance" in bounds else "(no tolerance)"
            else:
                judged = " ".join(
                    f"{'<=' if s == 'upper' else '>='} {shown(name, bounds[s])}"
                    for s in ("upper", "lower")
                    if s in bounds
                )
            failing = "" if entry["failing"] is None else f"{100 * entry['failing']:.3g} %"
            spread = [entry[key] for key in ("nominal", "mean", "std", "std_first_order")]
            rows.append(
                [
                    name,
                    *(shown(name, v) for v in spread),
                    shown(name, entry["percentiles"]["0.1"]),
                    shown(name, entry["percentiles"]["99.9"]),
                    judged,
                    failing,
                ]
            )
        lines = _columns(rows)
        lost = [f"{count} {why.replace('_', ' ')}" for why, count in self.unusable.items() if count]
        lines.append(
            f"yield: {100 * self.yield_fraction:.4g} % ± {100 * self.yield_stderr:.2g} % of {self.samples} "
            f"samples meet every judged target and limit (Monte Carlo {self.seconds:.3g} s)"
            + (f"; failing as unusable: {', '.join(lost)}" if lost else "")
        )
        lines.append(
            "inputs that matter most: sigma_i |d output / d input_i| at the design (first order), the same "
            "from the samples (Monte Carlo: regression slope x sigma_i; inputs whose slope is within noise, "
            f"{NOISE_SIGMAS:g} std / sqrt(samples), and first order 0 are left out), and the input's share "
            "of the first-order variance"
        )
        rows = [["output", "input", "first order", "Monte Carlo", "share"]]
        for name, groups in self.sensitivities.items():
            total = sum(entry["first_order"] ** 2 for entry in groups.values())
            noise = NOISE_SIGMAS * self.outputs[name]["std"] / math.sqrt(self.samples)
            groups = {g: e for g, e in groups.items() if e["first_order"] > 0 or e["monte_carlo"] > noise}
            for index, (group, entry) in enumerate(list(groups.items())[:top]):
                share = f"{100 * entry['first_order'] ** 2 / total:.3g} %" if total > 0 else "-"
                rows.append(
                    [
                        name if index == 0 else "",
                        group,
                        shown(name, entry["first_order"]),
                        shown(name, entry["monte_carlo"]),
                        share,
                    ]
                )
        lines.extend(_columns(rows))
        return "\n".join(lines)


def _columns(rows) -> list[str]:
    """Rows of cells as left-aligned text columns, indented by two spaces."""
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    return ["  " + "  ".join(cell.ljust(width) for cell, width in zip(row, widths)).rstrip() for row in rows]


def moved(entry: dict) -> bool:
    """Whether the tolerances move an output (an entry of ``ToleranceResult.outputs``): its
    spread, in the samples or to first order, is above rounding."""
    return max(entry["std"], entry["std_first_order"]) > ROUNDING_SPREAD * abs(entry["nominal"])


def _units(problem):
    units = {t.output: t.unit for t in problem.targets}
    units.update({lim.output: lim.unit for lim in problem.limits})
    units.update(problem.report_units)
    return units


def _bounds(tp):
    """{output: {"value", "tolerance"} of a target, {"upper", "lower"} of a limit} (SI)."""
    tolerances = dict(tp.target_tolerances)
    bounds = {}
    for target in tp.problem.targets:
        bounds[target.output] = {"value": float(target.value)}
        if target.output in tolerances:
            bounds[target.output]["tolerance"] = tolerances[target.output]
    for limit in tp.problem.limits:
        bounds.setdefault(limit.output, {}).update({side: float(getattr(limit, side)) for side in limit.sides})
    return bounds


def _passing(values, bounds):
    """(samples,) True where the output meets its row (NaN fails); None when not judged."""
    if "upper" in bounds or "lower" in bounds:
        ok = np.ones(values.shape, bool)
        if "upper" in bounds:
            ok &= values <= bounds["upper"]
        if "lower" in bounds:
            ok &= values >= bounds["lower"]
        return ok
    if "tolerance" in bounds:
        return np.abs(values - bounds["value"]) <= bounds["tolerance"]
    return None


def _groups(labels, contributions):
    """{group: sqrt(sum of squares of its variates' contributions)}, largest first."""
    sums = {}
    for label, value in zip(labels, contributions):
        sums[label] = sums.get(label, 0.0) + float(value) ** 2
    return {label: math.sqrt(total) for label, total in sums.items()}


def _batch_size(samples: int, chunk: int) -> int:
    """The samples of each batch: ``samples`` in the fewest batches of at most ``chunk``,
    as equal as they can be (one compiled shape)."""
    return -(-samples // -(-samples // chunk))


def _draw(tp, scene, key, samples, chunk, names, bar):
    """({name: (samples,)}, (sum_u, sum_uu, sum_o, sum_ou, used)): the samples' outputs,
    drawn in batches of at most ``chunk``, and the sums of the regression slopes over the
    samples whose outputs are all finite."""
    size = _batch_size(samples, chunk)
    chunks = -(-samples // size)
    dimension = len(tp.unit_std)
    drawn = {name: [] for name in names}
    sum_u, sum_uu, sum_o, sum_ou, used = np.zeros(dimension), np.zeros(dimension), {}, {}, 0
    for index in range(chunks):
        count = min(size, samples - index * size)
        u, result = _chunk(tp, scene, jax.random.fold_in(key, index), size, names)
        u = np.asarray(u)[:count]
        result = {name: np.asarray(value)[:count] for name, value in result.items()}
        for name in names:
            drawn[name].append(result[name])
        finite = np.all([np.isfinite(result[name]) for name in names], axis=0)
        u, used = u[finite], used + int(finite.sum())
        sum_u += u.sum(0)
        sum_uu += (u * u).sum(0)
        for name in names:
            sum_o[name] = sum_o.get(name, 0.0) + result[name][finite].sum()
            sum_ou[name] = sum_ou.get(name, 0.0) + result[name][finite] @ u
        bar.update(count)
    return {name: np.concatenate(parts) for name, parts in drawn.items()}, (sum_u, sum_uu, sum_o, sum_ou, used)


def monte_carlo(
    tp: ToleranceProblem,
    values: dict,
    *,
    samples: int = 10_000,
    seed: int = 0,
    chunk: int = CHUNK,
    progress: bool | None = None,
) -> ToleranceResult:
    """The design at ``values`` ({variable: SI}) under its tolerances, by Monte Carlo.

    Args:
        tp: the design and its tolerances (:func:`~magdesign.spec.tolerance.tolerance_problem_from_spec`).
        values: the design's variables (e.g. a solve's ``parameters``).
        samples: how many perturbed scenes to simulate (>= 1).
        seed: the PRNG seed (jax.random); a run is reproducible for the same seed and chunk
            (where its batches fit memory).
        chunk: samples per compiled batch, which bounds memory; a batch that runs out of
            this machine's memory is retried at half its size (a line on stderr says so).
        progress: a progress bar on stderr: True, False, or None (when stderr is a
            terminal and the run takes more than a second).

    Returns:
        A :class:`ToleranceResult`.
    """
    if samples < 1:
        raise ValueError(f"samples: expected at least 1, got {samples}")
    problem = tp.problem
    names = problem.outputs
    scene = tp.at(values)
    check_spreads(tp.inputs, scene)
    began = time.perf_counter()
    nominal, parts = _first_order(tp, scene)
    key = jax.random.key(seed)
    bar = tqdm(total=samples, unit="sample", delay=1.0, disable=None if progress is None else not progress, leave=False)
    while True:
        try:
            drawn, (sum_u, sum_uu, sum_o, sum_ou, used) = _draw(tp, scene, key, samples, chunk, tuple(names), bar)
            break
        except jax.errors.JaxRuntimeError as error:
            size = _batch_size(samples, chunk)
            if "RESOURCE_EXHAUSTED" not in str(error) or size == 1:
                raise
            # a batch that does not fit this machine's memory: the same draws' scheme in
            # batches of half the size (the samples then differ from a run that fitted)
            chunk = size // 2
            bar.reset()
            message = f"monte_carlo: a batch of {size} samples ran out of this machine's memory; batches of {chunk}"
            warnings.warn(message, SizeWarning, stacklevel=2)
    bar.close()
    seconds = time.perf_counter() - began

    bounds = _bounds(tp)
    passing = np.ones(samples, bool)
    nonfinite = ~np.all([np.isfinite(drawn[name]) for name in names], axis=0)
    passing &= ~nonfinite
    not_converged = np.zeros(samples, bool)
    if problem.converged is not None:
        not_converged = ~(drawn[problem.converged] >= 0.5) & ~nonfinite
        passing &= ~not_converged
    unit_std = tp.unit_std
    mean_u = sum_u / max(used, 1)
    var_u = np.maximum(sum_uu / max(used, 1) - mean_u**2, TINY)
    labels = tp.labels
    report = {}
    sensitivities = {}
    shown = [name for name in names if name != problem.converged]
    for name in shown:
        values_ = drawn[name]
        finite = values_[np.isfinite(values_)]
        rows = _passing(values_, bounds.get(name, {}))
        if rows is not None:
            passing &= rows
        first = np.asarray(parts[name])
        slope = (sum_ou[name] / max(used, 1) - mean_u * sum_o[name] / max(used, 1)) / var_u
        report[name] = {
            "unit": tp.scene.output_units.get(name, "1"),
            "nominal": float(nominal[name]),
            "mean": float(finite.mean()) if finite.size else math.nan,
            "std": float(finite.std()) if finite.size else math.nan,
            "std_first_order": float(np.sqrt(np.sum(first**2))),
            "percentiles": {
                f"{p:g}": float(np.percentile(finite, p)) if finite.size else math.nan for p in PERCENTILES
            },
            "bounds": bounds.get(name, {}),
            "failing": None if rows is None else float(1.0 - rows.mean()),
        }
        # the inputs that matter, for each judged or maximised output that the tolerances move
        judged = name in bounds or (problem.objective is not None and name == problem.objective.output)
        if judged and moved(report[name]):
            first_groups = _groups(labels, first)
            mc_groups = _groups(labels, slope * unit_std)
            order = sorted(first_groups, key=lambda g: -max(first_groups[g], mc_groups[g]))
            sensitivities[name] = {g: {"first_order": first_groups[g], "monte_carlo": mc_groups[g]} for g in order}
    fraction = float(passing.mean())
    return ToleranceResult(
        parameters={name: float(value) for name, value in values.items()},
        samples=samples,
        seed=seed,
        seconds=seconds,
        yield_fraction=fraction,
        yield_stderr=math.sqrt(fraction * (1.0 - fraction) / samples),
        outputs=report,
        sensitivities=sensitivities,
        unusable={"nonfinite": int(nonfinite.sum()), "not_converged": int(not_converged.sum())},
        values={name: drawn[name] for name in shown},
        units=_units(problem),
    )


def sigmas(tp: ToleranceProblem, values: dict) -> dict[str, float]:
    """{output: first-order standard deviation (SI)} of every output at design ``values``."""
    _, parts = _first_order(tp, tp.at(values))
    return {name: float(np.sqrt(np.sum(np.asarray(part) ** 2))) for name, part in parts.items()}


def shifted_problem(problem: Problem, k: float, sigma: dict) -> Problem:
    """The problem with each limit moved inwards by k sigma of its output (SI): upper
    bounds to upper - k sigma, lower bounds to lower + k sigma (scales kept).

    Raises:
        ValueError: a limit whose band is narrower than 2 k sigma (it cannot hold at k sigma).
    """
    limits = []
    for limit in problem.limits:
        margin = k * sigma[limit.output]
        upper = None if limit.upper is None else float(limit.upper) - margin
        lower = None if limit.lower is None else float(limit.lower) + margin
        if upper is not None and lower is not None and lower > upper:
            raise ValueError(f"{limit.output}: its band is narrower than +-{k:g} sigma ({margin:.6g} SI each side)")
        limits.append(Limit(limit.output, upper=upper, lower=lower, scale=limit.scale, unit=limit.unit))
    return eqx.tree_at(lambda p: p.limits, problem, tuple(limits))


class RobustResult(eqx.Module):
    """A design solved with its limits held at k first-order sigmas (:func:`robust_solve`).

    Attributes:
        design: the last solve (its limits the moved ones: upper - k sigma, lower + k sigma).
        k: the number of sigmas.
        sigma: {limited output: first-order standard deviation at the answer (SI)}.
        rounds: how many solves it took.
        settled: whether k sigma changed by less than ``rtol`` times each limit's scale in
            the last round (the limits hold at k sigma of the answer itself).
        why: "" or why it stopped unsettled.
    """

    design: DesignResult
    k: float
    sigma: dict
    rounds: int
    settled: bool
    why: str

    @property
    def status(self) -> str:
        """The last solve's status, or "sigma_not_settled" where it was successful but unsettled."""
        return self.design.status if self.settled or not self.design.successful else "sigma_not_settled"

    @property
    def successful(self) -> bool:
        return self.status == "successful"

    @property
    def parameters(self) -> dict:
        return self.design.parameters

    def to_json(self) -> dict:
        return {
            **self.design.to_json(),
            "status": self.status,
            "k": self.k,
            "sigma": dict(self.sigma),
            "rounds": self.rounds,
            "settled": self.settled,
            "why": self.why,
        }

    def table(self) -> str:
        held = ", ".join(
            f"{name} at {self.k:g} x {format_quantity(value, self.design.units.get(name))}"
            for name, value in self.sigma.items()
        )
        state = f"settled in {self.rounds} rounds" if self.settled else f"not settled after {self.rounds} rounds"
        return (
            f"{self.design.table()}\nlimits held at k sigma: {held} ({state}{': ' + self.why if self.why else ''})"
            f"\nstatus: {self.status}"
        )


def robust_solve(
    tp: ToleranceProblem, k: float, *, start: dict | None = None, rounds: int = ROBUST_ROUNDS, rtol: float = ROBUST_RTOL
) -> RobustResult:
    """Solve the design with every limit held at ``k`` first-order sigmas of its output:
    ``output + k sigma <= upper``, ``output - k sigma >= lower``.

    Sequentially (as SORA, Du and Chen 2004): solve with the limits moved inwards by k sigma
    of the current design, recompute sigma at the answer, and again, until k sigma moves by
    less than ``rtol`` times each limit's scale. Each solve reuses the nominal problem's
    compiled program (only the bounds change) and sigma needs first derivatives alone, so a
    costly field model is never differentiated three times. At the answer the limits hold
    at k sigma of the answer; sigma's own derivative does not enter the optimality
    conditions (where the active targets and limits fix the design, as in the default one,
    the answer is the same).

    Args:
        tp: the design and its tolerances.
        k: the number of sigmas (>= 0).
        start: {variable: SI} of the first solve (e.g. the nominal answer); default the
            variables' starts.
        rounds: the most solves.
        rtol: how little k sigma may still move, relative to each limit's scale.

    Returns:
        A :class:`RobustResult`; never raises for a design that cannot be made robust (see
        its ``status`` and ``why``).
    """
    if not (math.isfinite(k) and k >= 0):
        raise ValueError(f"k: expected a finite number >= 0, got {k!r}")
    problem = tp.problem
    values = {v.name: float(v.start) for v in problem.variables} if start is None else dict(start)
    sigma = sigmas(tp, values)
    limited = {lim.output: lim for lim in problem.limits}
    result, why, settled = None, "", False
    for round_ in range(1, rounds + 1):  # noqa: B007 (the rounds taken, returned below)
        try:
            shifted = shifted_problem(problem, k, sigma)
        except ValueError as error:
            why = str(error)
            break
        clipped = {v.name: min(max(values[v.name], float(v.lower)), float(v.upper)) for v in problem.variables}
        result = solve(shifted, start=clipped)
        values = result.parameters
        new = sigmas(tp, values)
        if not all(math.isfinite(new[name]) for name in limited):
            why = "sigma is not finite at the answer"
            sigma = new
            break
        settled = all(k * abs(new[name] - sigma[name]) <= rtol * float(lim.scale) for name, lim in limited.items())
        sigma = new
        if settled:
            break
    if result is None:  # the first shift failed: report the nominal solve
        result, round_ = solve(problem, start=start), 0
    return RobustResult(result, float(k), {name: sigma[name] for name in limited}, round_, settled, why)


def describe(tp: ToleranceProblem) -> dict:
    """{input: {"size": SI or fraction (a list of 3 per axis), "relative", "distribution",
    "written"}}: the tolerances as read, for reports."""
    return {
        t.name: {
            "size": np.asarray(t.size).tolist(),
            "relative": t.relative,
            "distribution": t.distribution,
            "written": t.written,
        }
        for t in tp.inputs
    }


def tolerance_lines(tp: ToleranceProblem) -> str:
    """One line per toleranced input ("magnet.remanence  3 %  normal (standard deviation)")."""
    kinds = {"normal": "normal (standard deviation)", "uniform": "uniform (half-width)"}
    width = max(len(t.name) for t in tp.inputs) + 2
    per = lambda t: " per sensor and axis" if t.name in AXES else ""  # noqa: E731
    return "\n".join(f"  {t.name:<{width}}{t.written}{per(t)}, {kinds[t.distribution]}" for t in tp.inputs)


def _far(run: ToleranceResult, name: str) -> bool:
    """Whether every bound of an output lies beyond its samples' range by more than that range."""
    entry = run.outputs[name]
    bounds = entry["bounds"]
    low, high = entry["percentiles"]["0.1"], entry["percentiles"]["99.9"]
    if "tolerance" in bounds:
        levels = [bounds["value"] - bounds["tolerance"], bounds["value"] + bounds["tolerance"]]
    else:
        levels = [bounds[side] for side in ("upper", "lower") if side in bounds]
    return all(level < low - (high - low) or level > high + (high - low) for level in levels)


def plot_tolerance(result: ToleranceResult, path, *, robust: ToleranceResult | None = None, title: str = "") -> None:
    """Write a PNG: a histogram of each target and limit output the tolerances move, with
    its bounds (dashed) and nominal value (dotted); a robust design's beside it."""
    runs = [("nominal", result, "C0")] + ([("robust", robust, "C2")] if robust is not None else [])
    names = [name for name, entry in result.outputs.items() if entry["bounds"] and moved(entry)]
    # an output far from its bounds in every run, failing nowhere, is listed, not drawn
    quiet = [name for name in names if all(run.outputs[name]["failing"] == 0 and _far(run, name) for _, run, _ in runs)]
    names = [name for name in names if name not in quiet]
    columns = min(3, max(1, len(names)))
    rows = max(1, -(-len(names) // columns))
    figure = Figure(figsize=(4.0 * columns, 2.9 * rows))
    axes = figure.subplots(rows, columns, squeeze=False).ravel()
    for axis in axes[len(names) :]:
        axis.set_visible(False)
    for axis, name in zip(axes, names):
        unit = result.units.get(name)
        scaled = lambda value: convert(np.asarray(value, float), unit) if unit else np.asarray(value, float)  # noqa: E731
        data = [scaled(run.values[name]) for _, run, _ in runs]
        finite = np.concatenate([d[np.isfinite(d)] for d in data])
        low, high = np.percentile(finite, [0.05, 99.95]) if finite.size else (0.0, 1.0)
        pad = 0.05 * (high - low) or 0.05 * abs(high) or 1.0
        edges = np.linspace(low - pad, high + pad, 61)
        for (label, run, color), values in zip(runs, data):
            failing = run.outputs[name]["failing"]
            axis.hist(values, bins=edges, color=color, alpha=0.5, label=f"{label}: {100 * failing:.3g} % fail")
            axis.axvline(float(scaled(run.outputs[name]["nominal"])), color=color, linestyle=":")
        bounds = result.outputs[name]["bounds"]
        lines = {side: bounds[side] for side in ("upper", "lower") if side in bounds}
        if "tolerance" in bounds:
            lines = {"lower": bounds["value"] - bounds["tolerance"], "upper": bounds["value"] + bounds["tolerance"]}
        far = []
        for side, level in lines.items():
            shown = float(scaled(level))
            if low - 4 * pad <= shown <= high + 4 * pad:
                axis.axvline(shown, color="C3", linestyle="--")
            else:
                far.append(f"{'<=' if side == 'upper' else '>='} {shown:.4g}")
        axis.set_xlabel(f"{name} ({unit or 'SI'})")
        axis.set_title(
            f"{name}: bounds dashed, nominal dotted" + (f"; {', '.join(far)} off the picture" if far else ""),
            fontsize=8,
        )
        axis.legend(fontsize=7)
        axis.grid(alpha=0.3)
    yields = [f"{label} {100 * run.yield_fraction:.3g} %" for label, run, _ in runs]
    figure.suptitle(f"{title}  yield: {', '.join(yields)}  ({result.samples} samples)".strip(), fontsize=10)
    if quiet:
        figure.text(0.01, 0.005, f"not drawn (no sample near its bounds): {', '.join(quiet)}", fontsize=7)
    figure.tight_layout(rect=(0, 0.03 if quiet else 0, 1, 1))
    with replaced(path) as temporary:
        figure.savefig(temporary, dpi=90)
