"""What accuracy costs in time: every model's fidelity levels, measured on this machine.

For each model, each level's error against the model's most exact level over a fixed set
of representative cases (below), and the warm, jitted time of one evaluation (median of
repeats). ``magdesign accuracy`` prints them side by side.

``quick=True`` (``magdesign accuracy --quick``) measures a cheaper tier of the same table: the
same cases with 3 repeats, the costly levels left out, and the dome's reference the default
mesh 2 x 16 in place of 6 x 48 (its row's error is 0, and it carries no estimate: that
compiles a second mesh): the dome at Reissner and 2 x 16, the spheres at 4 cells across and
the surface formulation's level 1, and neither the suspension pole nor the default design
(their programs compile for tens of seconds).

The cases:
- cylinder field: the dome-Hall sensor's magnet (R 1.5 mm, D 1 mm, 1.17 T) at 2,000 points on a
  fixed grid of sensor positions 1.5..20 radii from its centre, all directions; error is
  the largest |B - B_exact| / |B_exact|; one evaluation is one point (the batch time over
  the point count). float32 runs the exact kernel on float32 inputs.
- film field: Yan et al.'s (2021) film (T 6 mm, d 0.5 mm) 3 periods wide, at its 3 x 3 taxels
  (6 mm pitch, 3.5 mm below it) sheared by 0..3 mm (8 steps); the infinite
  film's closed form against the exact field of the finite film; error is the largest
  |B - B_finite| / |B_finite|; one evaluation is one point.
- sensor area averaging: the spin-valve matrix's active area (200 x 95 um) at 64 chip
  positions 0.6..2 mm above the 1 x 1 mm magnet; n = 1, 4, 16, 64 Gauss nodes against 256;
  error is the largest |B_n - B_256| / max |B_256|. One evaluation is one chip (timed in a
  batch of 4096).
- elastomer layer: normal stiffness, Hooke against the bonded-layer correction, for
  discs of shape factor 0.25..2 (Yan et al.'s Ecoflex, nu 0.49); one evaluation is one layer.
- dome: secant compliance at 5 N of domes like the dome-Hall sensor's (R_o 8 mm, t = 1.5, 2, 2.5 mm),
  Reissner and the axisymmetric model at five meshes against the finest (6 x 48); the meshes
  on the dome's ladder carry its own estimate (``dome_compliance(estimate=True)``), the
  estimate shown is the one at the case of the largest error; the time is that of the
  value alone (the estimate adds the companion mesh's solve).
- soft sphere: the method of moments for a Ni-Fe sphere (mu_r 1000, diameter 2 mm) in a
  uniform field, 4..16 cells across, against the exact M = 3 chi / (3 + chi) H0; error is
  the mean M's relative error; one evaluation is one solve. The surface formulation
  (:mod:`magdesign.fields.soft_surface`) of the same sphere at ladder levels 1..3, with its
  own error estimate beside the error (the panels' matrices are built once, on the first
  call, and reused; the time is a warm solve).
- suspension pole: the spring coefficient of the magnetic-suspension sensor's rod
  (``SUSPENSION_POLE``, the scene of examples/pole_plate.toml) at 8..16 cells
  along it (the example's 16 included) against 24 cells (itself not converged: the magnetic-suspension
  study's table puts it a few per cent from 32 cells), and the reduced (charge) level; one
  evaluation is the spring coefficient (five co-energy solves).
- default design: the parameters of the default design solved at each dome level, against
  the axisymmetric level (default mesh); error is the largest parameter move in metres (unit "m"), time is one solve.
"""

import statistics
import time
from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from matplotlib.figure import Figure

from magdesign._files import replaced
from magdesign._progress import say, stage
from magdesign.design import solve
from magdesign.fields import cylinder, film, soft, soft_surface
from magdesign.mechanics import LinearElastic, MooneyRivlin, dome_compliance, layer_stiffness
from magdesign.mechanics.dome import MESH_LADDER
from magdesign.scene import scene_from_spec
from magdesign.scene.effects import AreaAveraging
from magdesign.spec.design import default_spec, problem_from_spec
from magdesign.spec.levels import LADDERS, grid_factor
from magdesign.units import MU0, mm, um

# The levels measured; the QUICK_ ones are --quick's tier.
REPEATS, QUICK_REPEATS = 7, 3
DOME_MESHES = ((1, 12), (2, 12), (2, 16), (3, 24), (4, 32), (6, 48))  # the last is the reference
QUICK_DOME_MESHES = ((2, 16),)
AREA_POINTS_PER_SIDE = (1, 2, 4, 8)
AREA_REFERENCE_POINTS = 16
SOFT_SPHERE_CELLS, QUICK_SOFT_SPHERE_CELLS = (4, 8, 12, 16), (4,)
SATURATED_SPHERE_CELLS, QUICK_SATURATED_SPHERE_CELLS = (4, 8, 12), (4,)
SURFACE_LEVELS, QUICK_SURFACE_LEVELS = (1, 2, 3), (1,)
POLE_CELLS = (24, 8, 12, 16)  # the first is the reference

DOME_HALL_MAGNET = dict(radius=1.5 * mm, height=1 * mm, polarization=1.17)
SPIN_VALVE_MAGNET = dict(radius=0.5 * mm, height=1 * mm, polarization=1.3)
FILM_HALL_FILM = dict(period=6 * mm, thickness=0.5 * mm, polarization=0.085)
DOME_HALL_RESIN = MooneyRivlin(c10=0.1182e6, c01=0.1769e6)
# The magnetic-suspension sensor's scene without its pole's level (the levels are measured):
# a Ni-Fe rod through a 4 mm ball 0.4 mm above a magnet plate. The spring coefficient reads
# the magnet, the pole, the spring and the gap; the scene also needs a sensor.
SUSPENSION_POLE = {
    "magnet": {"shape": "plate", "radius": "5 mm", "height": "1 mm", "remanence": "0.2513 T"},
    "pole": {"ball_radius": "2 mm", "diameter": "1.2 mm", "permeability": 1000},
    "mechanics": {"model": "tilt", "spring": "7.2e-5 N/rad"},
    "geometry": {"gap": "0.4 mm"},
    "sensor": {"model": "gmr", "preset": "PANASONIC", "offset": "0.5 mm", "height": "0.1 mm"},
}


class Row(NamedTuple):
    """One measured level: error against the model's most exact level, and its cost.

    error is relative (unit "relative") except for decision rows (unit "m"); seconds is
    the warm time of one evaluation (s); cases says what one evaluation is. estimate is the
    level's own estimate of its error (same unit as error), what the model reports beside
    its answers, or None for a level that makes none: the table sets it beside the true
    error to show whether it is honest (it should bound the error).
    """

    model: str
    fidelity: str
    error: float
    seconds: float
    unit: str
    cases: str
    estimate: float | None = None


def _warm_seconds(fn, *args, per=1, quick=False):
    """Median wall time (s) of ``fn(*args)`` after one warm-up call, divided by ``per``
    (REPEATS runs, QUICK_REPEATS if ``quick``)."""
    jax.block_until_ready(fn(*args))
    times = []
    for _ in range(QUICK_REPEATS if quick else REPEATS):
        start = time.perf_counter()
        jax.block_until_ready(fn(*args))
        times.append(time.perf_counter() - start)
    return statistics.median(times) / per


def _field_points():
    """2,000 fixed sensor positions 1.5..20 radii from the dome-Hall magnet's centre (m)."""
    rng = np.random.default_rng(2026)
    directions = rng.normal(size=(2000, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    distances = DOME_HALL_MAGNET["radius"] * np.geomspace(1.5, 20.0, 2000)
    return directions * distances[:, None]


def _ladder_estimates(values, difference, ranks=None, model=None):
    """Each level's error estimate as the reports make it (:mod:`magdesign.spec.levels`):
    ``difference(a, b)`` of its value and the next finer level's (the finest level: the one
    below), times the grid factor of ``model``'s ladder between the levels' resolutions
    ``ranks`` (1 without a model). ``values`` run from the coarsest level to the finest."""
    order = None if model is None else next(ladder.order for ladder in LADDERS if ladder.model == model)
    estimates = []
    for i, value in enumerate(values):
        j = i + 1 if i + 1 < len(values) else i - 1
        factor = 1.0 if order is None else grid_factor(ranks[i], ranks[j], order)
        estimates.append(factor * difference(value, values[j]))
    return estimates


def _relative_error(approx, exact):
    return float(
        np.max(np.linalg.norm(np.asarray(approx) - np.asarray(exact), axis=-1) / np.linalg.norm(exact, axis=-1))
    )


def measure_field(quick=False):
    points = jnp.asarray(_field_points())
    exact_fn = jax.jit(lambda p: cylinder(p, **DOME_HALL_MAGNET, fidelity="exact"))
    dipole_fn = jax.jit(lambda p: cylinder(p, **DOME_HALL_MAGNET, fidelity="dipole"))
    exact = exact_fn(points)
    points32 = points.astype(jnp.float32)
    rows = []
    for fidelity, fn, args in (
        ("exact", exact_fn, points),
        ("dipole", dipole_fn, points),
        ("exact float32", exact_fn, points32),
    ):
        error = _relative_error(fn(args).astype(jnp.float64), exact)
        seconds = _warm_seconds(fn, args, per=len(points), quick=quick)
        rows.append(Row("cylinder field", fidelity, error, seconds, "relative", "one point"))
    return rows


def measure_film(quick=False):
    """The infinite film's closed form against the exact field of a film 3 periods wide."""
    # the film's field does not depend on y: the taxel columns x = -6, 0, 6 mm, sheared
    taxels = (np.arange(-1, 2)[:, None] * 6 * mm - np.linspace(0.0, 3 * mm, 8)[None, :]).ravel()
    x = jnp.asarray(np.resize(taxels, 2000))
    z = jnp.full(x.shape, 3.5 * mm)

    def field(periods):
        return jax.jit(lambda x, z: jnp.stack(film(x, z, **FILM_HALL_FILM, periods=periods), axis=-1))

    finite = field(3)(x, z)
    rows = []
    for name, periods in (("finite (3 periods)", 3), ("infinite", None)):
        fn = field(periods)
        error = _relative_error(fn(x, z), finite)
        seconds = _warm_seconds(fn, x, z, per=x.size, quick=quick)
        rows.append(Row("film field", name, error, seconds, "relative", "one point"))
    return rows


def measure_area_averaging(quick=False):
    """Area averaging of the field over a spin-valve's active area, n Gauss nodes."""
    xs, ys = np.meshgrid(np.linspace(-2 * mm, 2 * mm, 8), np.linspace(-2 * mm, 2 * mm, 8), indexing="ij")
    heights = np.linspace(1.1 * mm, 2.5 * mm, 64)  # 0.6..2 mm above the top face
    centres = jnp.asarray(np.stack([xs.ravel(), ys.ravel(), heights], axis=-1))
    # measured on the 64 chips 64 times over: the errors are the 64 chips', and the time is
    # that of 4096 chips (on 64 the call's fixed cost hides the work)
    batch = jnp.tile(centres, (64, 1))
    size = jnp.array([200 * um, 95 * um])

    def averaged(points_per_side):
        def fn(c):
            rotations = jnp.broadcast_to(jnp.eye(3), (c.shape[0], 3, 3))
            offsets, weights = AreaAveraging(size=size, points=points_per_side).sampling(rotations)
            return jnp.einsum("sqi,q->si", cylinder(c[:, None, :] + offsets, **SPIN_VALVE_MAGNET), weights)

        return jax.jit(fn)

    reference = averaged(AREA_REFERENCE_POINTS)(batch)
    scale = float(jnp.max(jnp.linalg.norm(reference, axis=-1)))

    def difference(a, b):
        return float(jnp.max(jnp.linalg.norm(a - b, axis=-1))) / scale

    functions = [averaged(per_side) for per_side in AREA_POINTS_PER_SIDE]
    values = [fn(batch) for fn in functions]
    estimates = _ladder_estimates(values, difference)
    return [
        Row(
            "sensor area averaging",
            f"n={per_side**2}",
            difference(value, reference),
            _warm_seconds(fn, batch, per=batch.shape[0], quick=quick),
            "relative",
            "one chip",
            estimate,
        )
        for per_side, fn, value, estimate in zip(AREA_POINTS_PER_SIDE, functions, values, estimates)
    ]


def measure_layer(quick=False):
    material = LinearElastic(E=83e3, nu=0.49)
    thickness = 3.5 * mm
    shape_factors = jnp.linspace(0.25, 2.0, 8)
    areas = jnp.pi * (2 * shape_factors * thickness) ** 2  # disc: S_f = a / (2 h)

    def stiffness(fidelity):
        return jax.jit(
            jax.vmap(
                lambda a: layer_stiffness(thickness=thickness, area=a, material=material, fidelity=fidelity).normal
            )
        )

    reference = stiffness("bonded")(areas)
    rows = []
    for fidelity in ("bonded", "hooke"):
        fn = stiffness(fidelity)
        error = float(jnp.max(jnp.abs(fn(areas) - reference) / reference))
        seconds = _warm_seconds(fn, areas, per=len(areas), quick=quick)
        rows.append(Row("elastomer layer", fidelity, error, seconds, "relative", "one layer"))
    return rows


def measure_dome(quick=False):
    meshes = QUICK_DOME_MESHES if quick else DOME_MESHES
    thicknesses = (1.5 * mm, 2.0 * mm, 2.5 * mm)

    def compliance(fidelity, mesh, **options):
        if fidelity == "axisymmetric":
            options["mesh"] = mesh
        return jax.jit(
            lambda t: dome_compliance(
                outer_radius=8 * mm, thickness=t, material=DOME_HALL_RESIN, max_force=5.0, fidelity=fidelity, **options
            )
        )

    levels = [("reissner", None)] + [("axisymmetric", mesh) for mesh in meshes]
    values, estimates, seconds = {}, {}, {}
    for fidelity, mesh in levels:
        stage(f"dome compliance at {fidelity}{'' if mesh is None else f' {mesh[0]}x{mesh[1]}'}")
        fn = compliance(fidelity, mesh)
        values[fidelity, mesh] = np.array([float(fn(t)) for t in thicknesses])
        seconds[fidelity, mesh] = _warm_seconds(fn, thicknesses[1], quick=quick)
        # off the ladder no estimate; --quick leaves the estimates' companion meshes out
        if fidelity == "axisymmetric" and mesh in MESH_LADDER and not quick:
            answers = [compliance(fidelity, mesh, estimate=True)(t) for t in thicknesses]
            estimates[fidelity, mesh] = np.array([float(a.error / a.value) for a in answers])
    reference = values["axisymmetric", meshes[-1]]
    rows = []
    for fidelity, mesh in levels:
        errors = np.abs(values[fidelity, mesh] - reference) / reference
        worst = int(np.argmax(errors))
        estimate = estimates.get((fidelity, mesh))
        rows.append(
            Row(
                "dome compliance",
                fidelity if mesh is None else f"{fidelity} {mesh[0]}x{mesh[1]}",
                float(errors[worst]),
                seconds[fidelity, mesh],
                "relative",
                "one 5 N load path",
                None if estimate is None else float(estimate[worst]),
            )
        )
    return rows


def measure_soft(quick=False):
    """The method of moments: a soft sphere (linear; saturated) against its exact answer."""
    rows = []
    field = jnp.array([0.0, 0.0, 1e-3])
    exact = 3.0 * 999.0 / 1002.0 * float(field[2]) / MU0
    solve_soft = jax.jit(soft.magnetization)
    ladder = QUICK_SOFT_SPHERE_CELLS if quick else SOFT_SPHERE_CELLS
    means, seconds = [], []
    for cells in ladder:
        body = soft.soft_body("sphere", radius=1 * mm, cells=cells, permeability=1000.0)
        external = jnp.broadcast_to(field, (len(body.index), 3))
        means.append(float(jnp.mean(solve_soft(body, external)[:, 2])))
        seconds.append(_warm_seconds(solve_soft, body, external, quick=quick))
    # one level has no companion: the quick tier's single row carries no estimate
    estimates = _ladder_estimates(means, lambda a, b: abs(a / b - 1), ladder, "soft") if len(ladder) > 1 else [None]
    for cells, mean, cost, estimate in zip(ladder, means, seconds, estimates):
        rows.append(
            Row(
                "soft sphere (moments)",
                f"{cells} cells across",
                abs(mean / exact - 1),
                cost,
                "relative",
                "one solve",
                estimate,
            )
        )
    for level in QUICK_SURFACE_LEVELS if quick else SURFACE_LEVELS:

        def surface(level=level):
            return soft_surface.mean_magnetization(
                "sphere", permeability=1000.0, external=field, radius=1 * mm, level=level
            )

        answer = surface()
        rows.append(
            Row(
                "soft sphere (surface)",
                f"level {level}, {answer.panels} panels",
                abs(float(answer.magnetization[2]) / exact - 1),
                _warm_seconds(lambda: surface().magnetization, quick=quick),
                "relative",
                "one solve",
                float(answer.error),
            )
        )
    applied, saturated = 1.0, _saturated_sphere(299.0, 2.2, 1.0)  # Fe in 1 T
    for cells in QUICK_SATURATED_SPHERE_CELLS if quick else SATURATED_SPHERE_CELLS:
        body = soft.soft_body("sphere", radius=1 * mm, cells=cells, permeability=300.0, saturation=2.2)
        external = jnp.broadcast_to(jnp.array([0.0, 0.0, applied]), (len(body.index), 3))
        error = abs(MU0 * float(jnp.mean(solve_soft(body, external)[:, 2])) / saturated - 1)
        rows.append(
            Row(
                "saturated Fe sphere, 1 T",
                f"{cells} cells across",
                error,
                _warm_seconds(solve_soft, body, external, quick=quick),
                "relative",
                "one solve",
            )
        )
    return rows


def measure_pole():
    """The magnetic-suspension pole's spring coefficient at its levels against the most cells."""
    outputs = eqx.filter_jit(lambda scene: scene.outputs(None)["spring_coefficient"])
    levels = [(f"moments {n} cells", dict(fidelity="moments", cells=n)) for n in POLE_CELLS]
    levels.append(("reduced", dict(fidelity="reduced", demagnetizing_factor=0.1)))
    values, seconds, rows = {}, {}, []
    for name, level in levels:
        stage(f"suspension pole spring at {name}")
        # the reduced level takes a demagnetizing factor in place of a permeability
        pole = {
            k: v for k, v in SUSPENSION_POLE["pole"].items() if level["fidelity"] == "moments" or k != "permeability"
        }
        scene = scene_from_spec({**SUSPENSION_POLE, "pole": pole | level})
        values[name], seconds[name] = float(outputs(scene)), _warm_seconds(outputs, scene)
    reference = values[levels[0][0]]
    # the moments levels from the fewest cells to the most, each with its estimate
    ranks, names = zip(*sorted((level["cells"], name) for name, level in levels if level["fidelity"] == "moments"))
    relative = _ladder_estimates([values[name] for name in names], lambda a, b: abs(a / b - 1), ranks, "pole")
    estimates = dict(zip(names, relative))
    for name, _ in levels:
        rows.append(
            Row(
                "suspension pole spring",
                name,
                abs(values[name] / reference - 1),
                seconds[name],
                "relative",
                "one spring coefficient",
                estimates.get(name),
            )
        )
    return rows


def _saturated_sphere(chi, saturation, applied):
    """J (T) of a uniformly magnetised sphere of the saturation law in a uniform field
    ``applied`` (T): the root of J - f(applied - J / 3), by bisection."""
    low, high = 0.0, min(saturation, 3.0 * applied)
    for _ in range(200):
        middle = 0.5 * (low + high)
        h = applied - middle / 3.0
        if middle < float(soft.law(jnp.array([0.0, 0.0, h]), chi, saturation)[2]):
            low = middle
        else:
            high = middle
    return 0.5 * (low + high)


def measure_default_design():
    """The decision: how far the default design moves between dome levels, and its cost."""
    solved = {}
    for fidelity in ("reissner", "axisymmetric"):
        stage(f"default design solved at {fidelity}")
        problem, _ = problem_from_spec(default_spec(), fidelity=fidelity)
        solve(problem)  # compile
        result = solve(problem)
        solved[fidelity] = (result, result.seconds)
    reference = solved["axisymmetric"][0].parameters
    return [
        Row(
            "default design",
            fidelity,
            max(abs(result.parameters[name] - reference[name]) for name in reference),
            seconds,
            "m",
            "one solve",
        )
        for fidelity, (result, seconds) in solved.items()
    ]


# (name, function, whether --quick's tier measures it): the pole's moments programs and the
# default design's axisymmetric solve compile for tens of seconds
MEASUREMENTS = (
    ("cylinder field", measure_field, True),
    ("film field", measure_film, True),
    ("sensor area averaging", measure_area_averaging, True),
    ("elastomer layer", measure_layer, True),
    ("dome compliance", measure_dome, True),
    ("soft magnetics", measure_soft, True),
    ("suspension pole", measure_pole, False),
    ("default design", measure_default_design, False),
)


def measure(progress=None, quick=False) -> list[Row]:
    """Measure every model (``quick``: the cheaper tier, see the module's docstring).
    ``progress`` (a text stream; default: the command's progress lines, see
    :mod:`magdesign._progress`) is told which one runs ("measuring dome compliance (5 of 6)
    ...") and then each row it measured, with its error and time."""

    def tell(text):
        if progress is None:
            say(text)
        else:
            print(text, file=progress, flush=True)

    rows = []
    chosen = [(name, fn) for name, fn, in_quick_tier in MEASUREMENTS if in_quick_tier or not quick]
    for number, (name, fn) in enumerate(chosen, start=1):
        tell(f"measuring {name} ({number} of {len(chosen)}) ...")
        measured = fn(quick=True) if quick else fn()
        for row in measured:
            tell(f"{row.model}, {row.fidelity}: error {_error(row)}, {_seconds(row.seconds)} per {row.cases}")
        rows.extend(measured)
    return rows


def table(rows) -> str:
    """The rows as a readable table: error (relative, or um for decisions) beside time."""
    width = max([24] + [len(row.model) + 2 for row in rows])
    head = f"{'model':<{width}}{'fidelity':<22}{'error':>14}{'estimate':>14}{'bounds':>8}{'time':>14}  per"
    lines = [head, "-" * (len(head) + 18)]
    for row in rows:
        estimate = "-" if row.estimate is None else _error(row, row.estimate)
        lines.append(
            f"{row.model:<{width}}{row.fidelity:<22}{_error(row):>14}{estimate:>14}{_bounds(row):>8}"
            f"{_seconds(row.seconds):>14}  {row.cases}"
        )
    return "\n".join(lines)


def _error(row, value=None):
    value = row.error if value is None else value
    return f"{value / um:.3g} um" if row.unit == "m" else f"{value:.2e}"


def _bounds(row):
    """Whether the level's estimate bounds its true error: "yes", "NO", or "-" (no estimate)."""
    if row.estimate is None:
        return "-"
    return "yes" if row.estimate >= row.error else "NO"


def _seconds(value):
    for unit, factor in (("s", 1.0), ("ms", 1e-3), ("us", 1e-6)):
        if value >= factor:
            return f"{value / factor:.3g} {unit}"
    return f"{value / 1e-9:.3g} ns"


def plot(rows, path):
    """Write a log-log PNG of error against time, one line per model (reference levels,
    whose error is 0 by definition, are left out)."""
    figure = Figure(figsize=(11, 4.5))
    axes = figure.subplots(1, 2)
    for axis, unit, label in ((axes[0], "relative", "relative error"), (axes[1], "m", "parameter move (m)")):
        for model in dict.fromkeys(row.model for row in rows if row.unit == unit):
            points = [(r.seconds, r.error, r.fidelity) for r in rows if r.model == model and r.error > 0]
            if not points:
                continue
            x, y, names = zip(*points)
            axis.loglog(x, y, "o-", label=model)
            for xi, yi, name in points:
                axis.annotate(name, (xi, yi), fontsize=7, xytext=(3, 3), textcoords="offset points")
        axis.set_xlabel("time per evaluation (s)")
        axis.set_ylabel(label)
        axis.grid(alpha=0.3, which="both")
        if axis.lines:
            axis.legend(fontsize=8)
    axes[0].set_title("model levels against the most exact level")
    axes[1].set_title("default design against the axisymmetric dome")
    figure.tight_layout()
    with replaced(path) as temporary:
        figure.savefig(temporary, dpi=110)
