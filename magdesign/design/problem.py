"""A design problem: free variables with bounds, targets, limits and an objective.

Everything is SI. The model is any jax-traceable callable mapping the variables' values
``{name: scalar (SI)}`` to named scalar outputs ``{output: scalar (SI)}``; targets, limits
and the objective refer to those outputs by name.

Numbers are stored as float64 arrays so that a jitted solve is compiled once per problem
structure (names, model, senses) and reused for new bounds, starts and target values.
"""

import functools
import weakref
from collections.abc import Callable, Mapping

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from magdesign._validation import _concrete


def _scalar(name, value):
    """A float64 scalar: a read-only numpy copy where concrete (cheap to read back; a copy,
    so that the problem does not change when the caller's array does), else the tracer."""
    concrete = _concrete(value)
    array = jnp.asarray(value, dtype=jnp.float64) if concrete is None else np.array(concrete, np.float64)
    if concrete is not None:
        array.flags.writeable = False
    if array.shape != ():
        raise ValueError(f"{name} must be a scalar, got shape {array.shape}")
    if concrete is not None and not np.isfinite(array):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return array


def _scale(name, scale, reference):
    """``scale`` if given (> 0), else |reference|, which must then be non-zero."""
    if scale is not None:
        scale = _scalar(f"{name}.scale", scale)
        concrete = _concrete(scale)
        if concrete is not None and concrete <= 0:
            raise ValueError(f"{name}.scale must be positive, got {float(concrete)!r}")
        return scale
    concrete = _concrete(reference)
    if concrete is not None and concrete == 0:
        raise ValueError(f"{name}: value 0 needs an explicit scale")
    return abs(reference)


class Variable(eqx.Module):
    """A free design parameter x in [lower, upper] (SI).

    Attributes:
        name: the key under which the model receives the value.
        lower, upper: bounds (SI), lower < upper.
        start: the default start (SI, inside the bounds); the midpoint if not given.
        scale: the solver works on (x - lower) / scale; default upper - lower.
        unit: display unit of reports ("mm"); SI if not given.
    """

    name: str = eqx.field(static=True)
    lower: Float[Array, ""]
    upper: Float[Array, ""]
    start: Float[Array, ""]
    scale: Float[Array, ""]
    unit: str | None = eqx.field(static=True)

    def __init__(self, name, lower, upper, start=None, scale=None, *, unit=None):
        self.name = name
        self.lower = _scalar(f"{name}.lower", lower)
        self.upper = _scalar(f"{name}.upper", upper)
        lo, hi = _concrete(self.lower), _concrete(self.upper)
        if lo is not None and hi is not None and not lo < hi:
            raise ValueError(f"{name}: lower bound {float(lo)!r} must be below upper bound {float(hi)!r}")
        self.start = 0.5 * (self.lower + self.upper) if start is None else _scalar(f"{name}.start", start)
        check_inside(name, self.start, self.lower, self.upper)
        self.scale = _scale(name, scale, self.upper - self.lower)
        self.unit = unit


def check_inside(name, value, lower, upper):
    """ValueError naming ``name`` unless lower <= value <= upper (tracers pass)."""
    concrete = [_concrete(v) for v in (value, lower, upper)]
    if all(c is not None for c in concrete):
        v, lo, hi = concrete
        if not (np.isfinite(v) and lo <= v <= hi):
            raise ValueError(f"{name}: start {float(v)!r} outside the bounds [{float(lo)!r}, {float(hi)!r}]")


class Target(eqx.Module):
    """Equality ``model output == value`` (SI), met to a relative tolerance of ``scale``.

    ``scale`` defaults to |value|; a target value of 0 needs an explicit scale.
    """

    output: str = eqx.field(static=True)
    value: Float[Array, ""]
    scale: Float[Array, ""]
    unit: str | None = eqx.field(static=True)

    def __init__(self, output, value, scale=None, *, unit=None):
        self.output = output
        self.value = _scalar(f"{output}.value", value)
        self.scale = _scale(output, scale, self.value)
        self.unit = unit


class Limit(eqx.Module):
    """Inequality ``lower <= model output <= upper`` (SI); either side may be None."""

    output: str = eqx.field(static=True)
    upper: Float[Array, ""] | None
    lower: Float[Array, ""] | None
    scale: Float[Array, ""]
    unit: str | None = eqx.field(static=True)

    def __init__(self, output, upper=None, lower=None, scale=None, *, unit=None):
        if upper is None and lower is None:
            raise ValueError(f"limit on {output}: give upper, lower or both")
        self.output = output
        self.upper = None if upper is None else _scalar(f"{output}.upper", upper)
        self.lower = None if lower is None else _scalar(f"{output}.lower", lower)
        if self.upper is not None and self.lower is not None:
            lo, hi = _concrete(self.lower), _concrete(self.upper)
            if lo is not None and hi is not None and not lo <= hi:
                raise ValueError(f"limit on {output}: lower {float(lo)!r} above upper {float(hi)!r}")
        reference = self.upper if self.upper is not None else self.lower
        self.scale = _scale(output, scale, reference)
        self.unit = unit

    @property
    def sides(self) -> tuple[str, ...]:
        """The bounded sides, each one inequality row of the solver: "upper", "lower"."""
        return tuple(side for side in ("upper", "lower") if getattr(self, side) is not None)


class Objective(eqx.Module):
    """Maximise (``sense="max"``) or minimise (``"min"``) a model output, times ``weight``."""

    output: str = eqx.field(static=True)
    sense: str = eqx.field(static=True)
    weight: Float[Array, ""]

    def __init__(self, output, sense="max", weight=1.0):
        if sense not in ("max", "min"):
            raise ValueError(f"objective sense must be 'max' or 'min', got {sense!r}")
        self.output = output
        self.sense = sense
        self.weight = _scalar("objective.weight", weight)


class Problem(eqx.Module):
    """Variables, a model of them, targets, limits and an optional objective.

    Attributes:
        model: ``model({variable: scalar (SI)}) -> {output: scalar (SI)}``, jax-traceable.
        variables: the free parameters (at least one).
        targets: equalities on outputs; limits: inequalities; objective: optional.
        report: further outputs to evaluate and report at the solution: names, or
            {name: display unit ("mm") or None for SI}.
        converged: optionally, the name of a model output that is 1 where every solver
            inside the model converged and 0 where one did not (a scene's
            "mechanics_converged"); a solution where it is below 1/2 gets the status
            "mechanics_not_converged", never "successful".
        fixed: {name: value (SI)} of model inputs held fixed, passed to the model beside
            the variables: the solver reports the implicit derivatives of the optimum with
            respect to them, and a sweep varies them (e.g. a scene's
            "mechanics.outer_radius").
    """

    model: Callable
    variables: tuple[Variable, ...]
    targets: tuple[Target, ...]
    limits: tuple[Limit, ...]
    objective: Objective | None
    report: tuple[str, ...] = eqx.field(static=True)
    report_units: tuple[tuple[str, str | None], ...] = eqx.field(static=True)
    converged: str | None = eqx.field(static=True)
    fixed_names: tuple[str, ...] = eqx.field(static=True)
    fixed_values: tuple[Float[Array, ""], ...]

    def __init__(self, model, variables, targets=(), limits=(), objective=None, report=(), converged=None, fixed=None):
        self.model = model
        self.variables = tuple(variables)
        self.targets = tuple(targets)
        self.limits = tuple(limits)
        self.objective = objective
        report_units = dict(report) if isinstance(report, Mapping) else dict.fromkeys(report)
        self.report = tuple(report_units)
        self.report_units = tuple(report_units.items())
        self.converged = converged
        fixed = dict(fixed or {})
        self.fixed_names = tuple(fixed)
        self.fixed_values = tuple(_scalar(f"fixed.{name}", value) for name, value in fixed.items())
        taken = sorted(set(self.fixed_names) & {v.name for v in self.variables})
        if taken:
            raise ValueError(f"fixed: {taken[0]!r} is a variable; a model input is either free or fixed")
        if not self.variables:
            raise ValueError("variables: a problem needs at least one free variable")
        for kind, names in (
            ("variables", [v.name for v in self.variables]),
            ("targets", [t.output for t in self.targets]),
            ("limits", [lim.output for lim in self.limits]),
        ):
            duplicates = sorted({n for n in names if names.count(n) > 1})
            if duplicates:
                raise ValueError(f"{kind}: duplicate name {duplicates[0]!r}")
        if not self.targets and not self.limits and objective is None:
            raise ValueError("targets: a problem needs a target, a limit or an objective")

    @property
    def outputs(self) -> tuple[str, ...]:
        """The model outputs the solver reads or reports, each once, in a fixed order."""
        names = [t.output for t in self.targets] + [lim.output for lim in self.limits]
        names += [self.objective.output] if self.objective is not None else []
        names += [self.converged] if self.converged is not None else []
        return tuple(dict.fromkeys(names + list(self.report)))

    @property
    def limit_rows(self) -> tuple[tuple[int, str], ...]:
        """(limit index, side) of each inequality row, in solver order."""
        return tuple((i, side) for i, lim in enumerate(self.limits) for side in lim.sides)


def check_outputs(problem: Problem, outputs) -> None:
    """Raise a ValueError, naming the output and the rule, unless the model's return
    ``outputs`` is a dict that holds every output ``problem`` reads, each a scalar. Shapes
    are static, so this holds while the model is traced too."""
    if not isinstance(outputs, Mapping):
        got = f"an array of shape {outputs.shape}" if hasattr(outputs, "shape") else f"a {type(outputs).__name__}"
        raise ValueError(f"model: the model must return a dict of scalar outputs {{name: value (SI)}}, got {got}")
    missing = [name for name in problem.outputs if name not in outputs]
    if missing:
        raise ValueError(f"{missing[0]}: not an output of the model (outputs: {sorted(outputs)})")
    for name in problem.outputs:
        value = outputs[name]
        if not (hasattr(value, "dtype") or isinstance(value, (int, float))) or jnp.iscomplexobj(value):
            kind = f"of dtype {value.dtype}" if hasattr(value, "dtype") else f"a {type(value).__name__}"
            raise ValueError(f"{name}: the model must return real scalar outputs (SI); {name!r} is {kind}")
        shape = jnp.shape(value)
        if shape != ():
            raise ValueError(f"{name}: the model must return a dict of scalar outputs; {name!r} has shape {shape}")


def per_problem(fn):
    """Memoise ``fn(problem)`` (host-side facts about a problem: arrays, names, layouts)
    for as long as that problem object lives: a solve of a small problem costs less than
    recomputing these from its fields each call. A Problem's own numbers are read-only
    copies (see _scalar); arrays inside its model are read once per problem object."""
    cache = {}

    @functools.wraps(fn)
    def memoised(problem):
        key = id(problem)
        entry = cache.get(key)
        if entry is not None and entry[0]() is problem:
            return entry[1]

        def forget(ref):
            if cache.get(key, (None,))[0] is ref:
                del cache[key]

        value = fn(problem)
        cache[key] = (weakref.ref(problem, forget), value)
        return value

    return memoised


# The spec each problem was built from (magdesign.spec.design.problem_from_spec), by id, for
# as long as the problem lives: a solved result writes it back with its answer in place.
_SOURCES = {}


def remember_source(problem: Problem, source: dict) -> None:
    """Keep ``source`` (a parsed spec) as the spec ``problem`` was built from (:func:`source_of`)."""
    key = id(problem)

    def forget(ref):
        if _SOURCES.get(key, (None,))[0] is ref:
            del _SOURCES[key]

    _SOURCES[key] = (weakref.ref(problem, forget), source)


def source_of(problem: Problem) -> dict | None:
    """The spec ``problem`` was built from (:func:`remember_source`), or None."""
    entry = _SOURCES.get(id(problem))
    return entry[1] if entry is not None and entry[0]() is problem else None
