"""The film-Hall sensor: a sinusoidally magnetised film over an elastomer layer, read by Hall
taxels.

Reproduces the design numbers of Yan et al., "Soft magnetic skin for super-resolution
tactile sensing with force self-decoupling", Sci. Robot. 6, eabc8801 (2021)
(docs/references.md): the attenuation distances of the film's field, the
sensitivity-range trade-off against the period T and its "balance" periods, the solved
(T, h) of the design, and the self-decoupling of normal and shear force.

    python studies/film_hall.py [--quick] [--out DIR]
"""

import copy
import math
import pathlib

import equinox as eqx
import jax
import jax.numpy as jnp
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from _report import Report, arguments, progress  # noqa: E402
from scipy.optimize import brentq  # noqa: E402

from magdesign.design import solve  # noqa: E402
from magdesign.fields import film, film_angle, film_magnitude  # noqa: E402
from magdesign.inverse import film_forces  # noqa: E402
from magdesign.scene import Loads, outputs, scene_from_spec, simulate, with_parameters  # noqa: E402
from magdesign.spec.design import load_spec, problem_from_spec  # noqa: E402
from magdesign.units import deg, kPa, mm, mT  # noqa: E402

NAME = "film_hall"
PAPER = "Yan et al., Sci. Robot. 6, eabc8801 (2021)"
EXAMPLE = pathlib.Path(__file__).resolve().parents[1] / "examples" / "film_hall.toml"

# Published numbers (Yan et al. 2021). "Design" is the Results section "Tactile sensor design";
# "Decoupling" the Results section "Sensor self-decoupling mechanism"; "Methods" the
# Materials and Methods section "Sensor characterization".
PERIOD = 6.0 * mm  # T, Design
FILM_THICKNESS = 0.5 * mm  # d, Design
LAYER_THICKNESS = 3.5 * mm  # h, Design
YOUNGS = 83 * kPa  # Ecoflex 00-50, Design
POISSON = 0.49  # "~0.5", Decoupling (Eq. 3); 0.49 keeps the layer compressible, as the example
ATTENUATION = {0.95: 2.9 * mm, 0.98: 3.8 * mm, 0.99: 4.5 * mm}  # Design, text on Fig. 1C
FIELD_FRACTION = 0.02  # "h is chosen within 3.8 mm where B >= 0.02 Bmax", Design
H_BOUND = 3.8 * mm  # same sentence
BALANCE_NORMAL = 5.81 * mm  # T1, Design (details in fig. S2, not in the text)
BALANCE_SHEAR = 6.24 * mm  # T2, Design
NORMAL_SENSITIVITY = 0.01 / kPa  # d(dB%)/dP, Eq. 2, for P <= 120 kPa; Design (fig. S3); a fraction of B per kPa
NORMAL_RANGE = 120 * kPa  # the range of that sensitivity; Design
SHEAR_SENSITIVITY = 0.1 / kPa  # for shear P <= 10 kPa; Design (fig. S3)
SHEAR_RANGE = 16 * kPa  # shear measured up to 16 kPa (0.27 /kPa above 10 kPa); Design
FACE = 18 * mm  # the film is 18 mm x 18 mm; Methods, "Characterization for super-resolution"
STEP, STEPS = 0.25 * mm, 7  # 7 x 7 displacement loads, 0.25 mm steps; Methods, "self-decoupling"
RMSE_NORMAL = 0.15  # N, Eq. 3 against measurement, Decoupling (Fig. 2F)

# Tolerances of the comparison (why each, in the report's "why" column)
DISTANCE_TOL = 0.025  # relative
BALANCE_TOL = 0.05  # relative
BONDED_TOL = 0.25  # relative


def base_spec() -> dict:
    """examples/film_hall.toml with the published stack written in, and no effects: the
    paper's numbers are about the film's own field (a background would count as signal)."""
    spec = load_spec(EXAMPLE)
    spec["scene"] = {"effects": []}
    spec["magnet"].update(period=PERIOD, thickness=FILM_THICKNESS)
    spec["mechanics"].update(thickness=LAYER_THICKNESS, youngs_modulus=YOUNGS, poisson_ratio=POISSON)
    return spec


def varied(spec: dict, **tables) -> dict:
    """A copy of ``spec`` with ``tables={key: value}`` merged in, e.g. magnet={"periods": 3}."""
    spec = copy.deepcopy(spec)
    for table, values in tables.items():
        spec.setdefault(table, {}).update(values)
    return spec


def centre(scene) -> int:
    rows, cols = scene.grid
    return (rows // 2) * cols + cols // 2


def contact_area(scene) -> float:
    return float(scene.layer.contact_area)


@eqx.filter_jit
def taxel_field(scene, loads):
    """(n, 3) field (T) at the central taxel, scene frame (z up, towards the film)."""
    return simulate(scene, loads).field[:, centre(scene)]


def field_angle(field):
    """The field angle atan2(Bx, Bz) of the film frame (its depth axis is the scene's -z)."""
    return film_angle(field[..., 0], -field[..., 2])


@eqx.filter_jit
def pressure_sensitivities(scene):
    """(d ln|B| / dP, d angle / d tau) at rest at the central taxel (1/Pa, rad/Pa): the
    paper's d(dB%)/dP of Eq. 2 and, at rest, its dR_B/dP (R_B = tan angle)."""
    area = scene.layer.contact_area

    def log_magnitude(pressure):
        return jnp.log(jnp.linalg.norm(taxel_field(scene, Loads(pressure[None] * area))[0]))

    def angle(pressure):
        shear = jnp.stack([pressure * area, 0.0])[None]
        return field_angle(taxel_field(scene, Loads(jnp.zeros(1), shear))[0])

    zero = jnp.zeros(())
    # a shear u moves the film, so the taxel sees the pattern at x = -u: the angle turns by -k u
    return jax.jvp(log_magnitude, (zero,), (jnp.ones(()),))[1], -jax.jvp(angle, (zero,), (jnp.ones(()),))[1]


@eqx.filter_jit
def period_outputs(scene, loads, period):
    """The scene's outputs and pressure sensitivities with its period set to ``period``."""
    scene = with_parameters(scene, {"magnet.period": period})
    normal, shear = pressure_sensitivities(scene)
    return outputs(scene, loads) | {"normal_pressure": normal, "shear_pressure": shear}


def attenuation_distance(fraction, magnitude) -> float:
    """Depth (m) below the film's face where ``magnitude(z)`` has fallen by ``fraction``."""
    face = magnitude(0.0)
    return brentq(lambda z: magnitude(z) / face - (1.0 - fraction), 0.0, 30 * mm, xtol=1e-12)


def finite_magnitude(periods):
    """|B| (T, per tesla of J0) at depths z (a float or an array) below the centre of a film
    ``periods`` wide."""
    field = jax.jit(
        lambda z: jnp.hypot(*film(0.0, z, period=PERIOD, thickness=FILM_THICKNESS, polarization=1.0, periods=periods))
    )
    return lambda z: float(field(z)) if np.ndim(z) == 0 else np.asarray(field(jnp.asarray(z)))


def percent(value, published) -> str:
    return f"{100 * (value / published - 1):+.1f} %"


def verdict(value, published, tolerance) -> str:
    """The relative difference and whether it is within ``tolerance`` (relative)."""
    inside = abs(value / published - 1) <= tolerance
    return f"{percent(value, published)} ({'within' if inside else 'outside'} {100 * tolerance:g} %)"


# ---------------------------------------------------------------------------------------


def attenuation():
    """Attenuation distances: infinite film (closed form) and finite strips (exact)."""
    progress("attenuation distances")
    infinite = {
        a: attenuation_distance(
            a, lambda z: float(film_magnitude(z, period=PERIOD, thickness=FILM_THICKNESS, polarization=1.0))
        )
        for a in ATTENUATION
    }
    strips = {}
    for periods in (1, 3):
        magnitude = finite_magnitude(periods)
        strips[periods] = {a: attenuation_distance(a, magnitude) for a in ATTENUATION}
    # The k for which e^{-kz}, rounded to 0.1 mm, gives all three published distances
    low = max(math.log(1 / (1 - a)) / (z + 0.05 * mm) for a, z in ATTENUATION.items())
    high = min(math.log(1 / (1 - a)) / (z - 0.05 * mm) for a, z in ATTENUATION.items())
    return infinite, strips, (low, high)


def shear_loads(scene):
    """Rest, then the published largest shear pressure: shear_phase_max is k u_x there."""
    return Loads(jnp.zeros(2), jnp.array([[0.0, 0.0], [SHEAR_RANGE * contact_area(scene), 0.0]]))


def shear_balance(scene, loads) -> float:
    """T2: the period whose field angle reaches 90 deg at the published largest shear."""
    return brentq(
        lambda t: float(period_outputs(scene, loads, jnp.asarray(t))["shear_phase_max"]) - math.pi / 2,
        3 * mm,
        20 * mm,
        xtol=1e-12,
    )


def trade_off(spec, quick):
    """Sensitivity and range against T at the published h, d, E; the balance periods."""
    progress("sensitivity-range trade-off against T")
    scene = scene_from_spec(spec)
    loads = shear_loads(scene)
    periods = np.linspace(3 * mm, 12 * mm, 31 if quick else 181)
    curves = jax.vmap(lambda t: period_outputs(scene, loads, t))(jnp.asarray(periods))
    curves = {key: np.asarray(value) for key, value in curves.items()}
    # shear range: the shear pressure at which the field angle reaches 90 deg (u_x linear in load)
    curves["shear_range"] = SHEAR_RANGE * (math.pi / 2) / curves["shear_phase_max"]

    balance_normal = brentq(
        lambda t: float(period_outputs(scene, loads, jnp.asarray(t))["field_fraction"]) - FIELD_FRACTION,
        3 * mm,
        12 * mm,
        xtol=1e-12,
    )
    balance_shear = shear_balance(scene, loads)
    at_published = period_outputs(scene, loads, jnp.asarray(PERIOD))
    return periods, curves, balance_normal, balance_shear, {k: float(v) for k, v in at_published.items()}, scene


def calibrated_shear(spec):
    """T2 again, with the layer's shear modulus set so that dR_B/dP at rest at the published
    T is the published 0.1 /kPa: G = k h / 0.1 kPa^-1 (Hooke layer, E = 2 (1 + nu) G)."""
    k = 2 * math.pi / PERIOD
    shear_modulus = k * LAYER_THICKNESS / SHEAR_SENSITIVITY
    stiff = varied(spec, mechanics={"youngs_modulus": 2 * (1 + POISSON) * shear_modulus})
    scene = scene_from_spec(stiff)
    t2 = shear_balance(scene, shear_loads(scene))
    return shear_modulus, t2


def bonded_face(spec):
    """d ln|B| / dP at rest for the whole 18 x 18 mm face pressed on a bonded layer."""
    scene = scene_from_spec(varied(spec, mechanics={"fidelity": "bonded", "contact_area": FACE**2}))
    return float(pressure_sensitivities(scene)[0])


def design(spec):
    """The example's design problem (T and h free) on the published stack, solved."""
    progress("design solve (T, h): compiles the solver")
    design_spec = varied(spec)  # the example's [design] and [load] tables, no background
    problem, _ = problem_from_spec(design_spec)
    return solve(problem), design_spec


def decoupling(spec):
    """The 7 x 7 displacement grid of the paper's decoupling test, as forces on the layer."""
    progress("decoupling: 7 x 7 normal x shear grid")
    steps = STEP * np.arange(STEPS)  # 0 .. 1.5 mm
    dz, dx = (a.ravel() for a in np.meshgrid(steps, steps, indexing="ij"))
    rows = {}
    for periods in (None, 1, 3):
        scene = scene_from_spec(varied(spec, magnet={} if periods is None else {"periods": periods}))
        stiffness = scene.layer.stiffness
        loads = Loads(
            jnp.asarray(dz * float(stiffness.normal)),
            jnp.stack([jnp.asarray(dx * float(stiffness.shear)), jnp.zeros(dx.size)], axis=-1),
        )
        field = taxel_field(scene, loads)
        magnitude = np.asarray(jnp.linalg.norm(field, axis=-1)).reshape(STEPS, STEPS)  # [dz, dx]
        angle = np.asarray(field_angle(field)).reshape(STEPS, STEPS)
        fz, fx = film_forces(scene, field[0], field)  # Eq. 3 with c1 = c2 = 1, b1 = b2 = 0
        rows[periods] = {
            "steps": steps,
            "magnitude": magnitude,
            "angle": angle,
            # largest change of |B| under shear at a fixed normal load, relative to |B|
            "magnitude_coupling": float(np.max((magnitude.max(1) - magnitude.min(1)) / magnitude.mean(1))),
            # largest change of the angle under normal load at a fixed shear
            "angle_coupling": float(np.max(angle.max(0) - angle.min(0))),
            "rmse_normal": float(np.sqrt(np.mean((np.asarray(fz) - np.asarray(loads.normal)) ** 2))),
            "rmse_shear": float(np.sqrt(np.mean((np.asarray(fx) - np.asarray(loads.shear[:, 0])) ** 2))),
            "max_normal": float(loads.normal.max()),
            "max_shear": float(loads.shear[:, 0].max()),
        }
    return rows


# ---------------------------------------------------------------------------------------


def attenuation_figure(report, strips):
    z = np.linspace(0, 6 * mm, 200)
    fig, ax = plt.subplots(figsize=(6, 4))
    infinite = np.asarray(film_magnitude(z, period=PERIOD, thickness=FILM_THICKNESS, polarization=1.0))
    ax.semilogy(z / mm, infinite / infinite[0], label="infinite film (closed form)")
    for periods in strips:
        magnitude = finite_magnitude(periods)
        values = magnitude(z)
        ax.semilogy(z / mm, values / values[0], "--", label=f"film {periods} period(s) wide (exact)")
    for fraction, depth in ATTENUATION.items():
        ax.plot(depth / mm, 1 - fraction, "ko")
    ax.plot([], [], "ko", label="published (Fig. 1C text)")
    ax.axvline(LAYER_THICKNESS / mm, color="grey", lw=0.8, ls=":")
    ax.set(
        xlabel="depth z below the film's face (mm)",
        ylabel="|B|(z) / |B|(0)",
        title=f"T = {PERIOD / mm:g} mm, d = {FILM_THICKNESS / mm:g} mm",
    )
    ax.legend(fontsize=8)
    report.figure(
        fig,
        "attenuation.png",
        "Decay of the film's |B| below its face at the taxel's lateral "
        "position; dots: the published 95/98/99 % attenuation distances; dotted: h = 3.5 mm.",
    )


def trade_off_figure(report, periods, curves, balance_normal, balance_shear, calibrated_t2):
    t = periods / mm
    fig, axes = plt.subplots(2, 2, figsize=(10, 6.5), sharex=True)
    (sn, ss), (rn, rs) = axes
    sn.plot(t, curves["normal_pressure"] * kPa)
    sn.set(ylabel="d ln|B| / dP (1/kPa)", title="normal force: sensitivity (Eq. 2)")
    ss.plot(t, curves["shear_pressure"] * kPa)
    ss.set(ylabel="d angle / dP = dR_B/dP at rest (1/kPa)", title="shear force: sensitivity")
    rn.semilogy(t, 100 * curves["field_fraction"], "C1")
    rn.axhline(100 * FIELD_FRACTION, color="C1", ls=":", label="2 % (paper's rule)")
    rn.set(
        xlabel="period T (mm)",
        ylabel="|B| at the taxel / at the face (%)",
        title="normal force: field kept at the taxel",
    )
    rs.plot(t, curves["shear_range"] / kPa, "C1")
    rs.axhline(SHEAR_RANGE / kPa, color="C1", ls=":", label="16 kPa (published range)")
    rs.set(xlabel="period T (mm)", ylabel="shear at 90 deg of field angle (kPa)", title="shear force: range")
    for column, ours, published in (
        (axes[:, 0], balance_normal, BALANCE_NORMAL),
        (axes[:, 1], balance_shear, BALANCE_SHEAR),
    ):
        for ax in column:
            ax.axvline(ours / mm, color="k", lw=1, label=f"magdesign balance {ours / mm:.2f} mm")
            ax.axvline(published / mm, color="k", ls="--", lw=1, label=f"published {published / mm:.2f} mm")
    for ax in axes[:, 1]:
        ax.axvline(
            calibrated_t2 / mm, color="g", lw=1, label=f"G from the published 0.1/kPa: {calibrated_t2 / mm:.2f} mm"
        )
    for ax in axes.ravel():
        ax.legend(fontsize=7)
    fig.tight_layout()
    report.figure(
        fig,
        "trade_off.png",
        "Sensitivity (top; falls as 1/T) and what bounds the range (bottom; "
        "rises with T) against the period at the published d = 0.5 mm, h = 3.5 mm, E = 83 kPa; the "
        "balance is the shortest T whose range covers the need (dotted lines).",
    )


def decoupling_figure(report, rows):
    fig, axes = plt.subplots(len(rows), 2, figsize=(10, 3.2 * len(rows)), squeeze=False)
    for (periods, row), (left, right) in zip(rows.items(), axes):
        steps = row["steps"] / mm
        name = "infinite film" if periods is None else f"film {periods} period(s) wide"
        for j in range(STEPS):
            left.plot(steps, row["magnitude"][:, j] / mT, "o-", ms=3, label=f"dX = {steps[j]:.2f} mm")
            right.plot(steps, row["angle"][j, :] / deg, "o-", ms=3, label=f"dZ = {steps[j]:.2f} mm")
        left.set(xlabel="normal displacement dZ (mm)", ylabel="|B| at the taxel (mT)", title=f"{name}: |B|")
        right.set(xlabel="shear displacement dX (mm)", ylabel="field angle atan2(Bx, Bz) (deg)", title=f"{name}: angle")
    axes[0, 0].legend(fontsize=6, title="one line per shear", title_fontsize=6)
    axes[0, 1].legend(fontsize=6, title="one line per normal", title_fontsize=6)
    fig.tight_layout()
    report.figure(
        fig,
        "decoupling.png",
        "The paper's 7 x 7 grid of displacement loads (0.25 mm steps): "
        "|B| against normal displacement with one line per shear (lines on top of each other where "
        "shear does not change |B|), and the angle against shear with one line per normal load.",
    )


# ---------------------------------------------------------------------------------------


def main(argv=None):
    args = arguments(NAME, argv, __doc__)
    report = Report(
        NAME, f"Film-Hall sensor: sinusoidally magnetised film over Hall taxels ({PAPER})", args.out, args.quick
    )
    spec = base_spec()

    infinite, strips, (k_low, k_high) = attenuation()
    periods, curves, t1, t2, published_design, scene = trade_off(spec, args.quick)
    g_nominal = float(scene.layer.material.shear_modulus)
    g_calibrated, t2_calibrated = calibrated_shear(spec)
    bonded = bonded_face(spec)
    result, design_spec = design(spec)
    rows = decoupling(spec)
    progress("report")

    normal_hooke, shear_hooke = published_design["normal_pressure"], published_design["shear_pressure"]
    solved_t = result.parameters["magnet.period"]
    solved_h = result.parameters["mechanics.thickness"]
    coupled = rows[3]
    ideal = rows[None]
    s_target = result.targets["normal_sensitivity"]["target"]

    above = [z / infinite[a] - 1 for a, z in ATTENUATION.items()]
    distance_why = (
        f"infinite film, exact; tolerance {100 * DISTANCE_TOL:g} %: the published distances lie "
        f"{100 * min(above):.1f}..{100 * max(above):.1f} % above e^(-kz) at T = {PERIOD / mm:g} mm, as if "
        f"read off Fig. 1C's curve (rounded to 0.1 mm they fit e^(-kz) only for "
        f"T = {2 * math.pi / k_high / mm:.2f}..{2 * math.pi / k_low / mm:.2f} mm)"
    )
    comparison = [
        {
            "quantity": f"attenuation distance, {int(100 * a)} % (\\|B\\| = {100 * (1 - a):.0f} % of the face value)",
            "published": f"{z / mm:.1f} mm",
            "source": "Design, Fig. 1C",
            "magdesign": f"{infinite[a] / mm:.3f} mm",
            "difference": verdict(infinite[a], z, DISTANCE_TOL),
            "why": distance_why if i == 0 else "as above",
        }
        for i, (a, z) in enumerate(ATTENUATION.items())
    ]
    comparison += [
        {
            "quantity": "balance period T1, normal force",
            "published": f"{BALANCE_NORMAL / mm:.2f} mm",
            "source": "Design (fig. S2)",
            "magdesign": f"{t1 / mm:.3f} mm",
            "difference": verdict(t1, BALANCE_NORMAL, BALANCE_TOL),
            "why": (
                f"our definition (fig. S2's is not in the text): the shortest T, i.e. the most sensitive, whose "
                f"field at the taxel (h = 3.5 mm) keeps the paper's 2 % of the face field; tolerance "
                f"{100 * BALANCE_TOL:g} % for a definition inferred from the text"
            ),
        },
        {
            "quantity": "balance period T2, shear force",
            "published": f"{BALANCE_SHEAR / mm:.2f} mm",
            "source": "Design (fig. S2)",
            "magdesign": f"{t2 / mm:.3f} mm",
            "difference": verdict(t2, BALANCE_SHEAR, BALANCE_TOL),
            "why": (
                f"our definition: the shortest T whose field angle stays within 90 deg up to the published "
                f"{SHEAR_RANGE / kPa:g} kPa of shear, with the Hooke layer's nominal G = E / 2(1 + nu) = "
                f"{g_nominal / kPa:.1f} kPa; the published shear sensitivity implies G = {g_calibrated / kPa:.1f} kPa "
                "(next rows)"
            ),
        },
        {
            "quantity": "balance period T2, G from the published shear sensitivity",
            "published": f"{BALANCE_SHEAR / mm:.2f} mm",
            "source": "Design (fig. S2, fig. S3)",
            "magdesign": f"{t2_calibrated / mm:.3f} mm",
            "difference": verdict(t2_calibrated, BALANCE_SHEAR, BALANCE_TOL),
            "why": (
                f"same definition, G = {g_calibrated / kPa:.1f} kPa set so that dR_B/dP at rest is the "
                f"published 0.1 /kPa at T = 6 mm; tolerance {100 * BALANCE_TOL:g} %"
            ),
        },
        {
            "quantity": "shear sensitivity dR_B/dP at rest",
            "published": f"{SHEAR_SENSITIVITY * kPa:g} /kPa",
            "source": "Design (fig. S3), shear <= 10 kPa",
            "magdesign": f"{shear_hooke * kPa:.4f} /kPa",
            "difference": percent(shear_hooke, SHEAR_SENSITIVITY),
            "why": (
                "Hooke layer, nominal G from E = 83 kPa, nu = 0.49: k h / G; the built sensor is stiffer in "
                "shear (its value is also a fit over 0..10 kPa, where the model's tan(kx) steepens further)"
            ),
        },
        {
            "quantity": f"normal sensitivity d(dB%)/dP (Eq. 2), one {contact_area(scene) / mm**2:g} mm^2 cell, Hooke layer",
            "published": f"{NORMAL_SENSITIVITY * kPa:g} /kPa",
            "source": "Design (fig. S3), P <= 120 kPa",
            "magdesign": f"{normal_hooke * kPa:.4f} /kPa",
            "difference": percent(normal_hooke, NORMAL_SENSITIVITY),
            "why": (
                "k h / E: a layer free to bulge under one cell's contact is far softer than the bonded, cast "
                "layer. 0.01 /kPa read as a fraction of B per kPa (1 %/kPa; section 2 says why); read as "
                f"0.01 %/kPa it would lie {normal_hooke / (NORMAL_SENSITIVITY / 100):.0f} times below the model"
            ),
        },
        {
            "quantity": "normal sensitivity, whole 18 x 18 mm face on a bonded layer",
            "published": f"{NORMAL_SENSITIVITY * kPa:g} /kPa",
            "source": "Design (fig. S3), P <= 120 kPa",
            "magdesign": f"{bonded * kPa:.4f} /kPa",
            "difference": verdict(bonded, NORMAL_SENSITIVITY, BONDED_TOL),
            "why": (
                "layer fidelity 'bonded' (shape-factor correction, Gent & Lindley) under the full face; "
                f"tolerance {100 * BONDED_TOL:g} %: that correction is approximate at shape factor ~1.5 and the contact of the "
                "paper's test is not stated"
            ),
        },
        {
            "quantity": "solved period T (design solve)",
            "published": f"{PERIOD / mm:g} mm",
            "source": "Design",
            "magdesign": f"{solved_t / mm:.3f} mm ({result.status})",
            "difference": percent(solved_t, PERIOD),
            "why": (
                f"not a reproduction: the 2 % rule fixes only h/T; the spec's second target "
                f"({s_target / mT:g} mT/N at J0 = {float(scene.magnetization) / mT:g} mT, from the example) is "
                f"not published and sets the scale; the paper picked T = 6 mm between T1 and T2"
            ),
        },
        {
            "quantity": "solved layer h (design solve)",
            "published": f"{LAYER_THICKNESS / mm:g} mm",
            "source": "Design",
            "magdesign": f"{solved_h / mm:.3f} mm",
            "difference": percent(solved_h, LAYER_THICKNESS),
            "why": "as above; the paper also kept h below its 2 % bound (3.5 < 3.8 mm)",
        },
        {
            "quantity": "h / T from the 2 % rule",
            "published": f"<= {H_BOUND / PERIOD:.4f} (3.8 mm / 6 mm)",
            "source": "Design",
            "magdesign": f"{solved_h / solved_t:.4f}",
            "difference": percent(solved_h / solved_t, H_BOUND / PERIOD),
            "why": (
                f"the solve's field_fraction = {FIELD_FRACTION:g} target; the same "
                f"{percent(infinite[0.98], ATTENUATION[0.98])} as the 98 % distance "
                f"({infinite[0.98] / mm:.3f} vs {ATTENUATION[0.98] / mm:g} mm)"
            ),
        },
        {
            "quantity": "\\|B\\| change under shear at fixed normal load",
            "published": "none (B constant)",
            "source": "Decoupling, Fig. 2G",
            "magdesign": f"{ideal['magnitude_coupling']:.1e} (infinite film); "
            f"{coupled['magnitude_coupling']:.1e} (18 mm film)",
            "difference": "-",
            "why": "an infinite film decouples exactly; a film 3 periods wide has edges, so \\|B\\| moves with shear",
        },
        {
            "quantity": "field angle change under normal load at fixed shear",
            "published": "none (R_B constant)",
            "source": "Decoupling, Fig. 2J",
            "magdesign": f"{ideal['angle_coupling'] / deg:.1e} deg (infinite); "
            f"{coupled['angle_coupling'] / deg:.2f} deg (18 mm film)",
            "difference": "-",
            "why": "as above",
        },
        {
            "quantity": "RMSE of Fz from Eq. 3",
            "published": f"{RMSE_NORMAL:g} N",
            "source": "Decoupling, Fig. 2F",
            "magdesign": f"{ideal['rmse_normal']:.1e} N (infinite); {coupled['rmse_normal']:.3f} N (18 mm film)",
            "difference": "-",
            "why": (
                "not the same error: the paper fits c1, b1 to measurements; here Eq. 3 with c1 = 1, b1 = 0 "
                "reads the model's own forces, exact for the infinite film; the 18 mm film's RMSE is the "
                f"closed form's own error (loads up to {coupled['max_normal']:.2f} N)"
            ),
        },
    ]
    report.comparison(comparison)

    # --- the field and the paper's Eq. 1 ------------------------------------------------
    k = 2 * math.pi / PERIOD
    ours = float(
        film_magnitude(
            LAYER_THICKNESS, period=PERIOD, thickness=FILM_THICKNESS, polarization=float(scene.magnetization)
        )
    )
    printed = float(scene.magnetization) * math.expm1(k * FILM_THICKNESS) * math.exp(-k * LAYER_THICKNESS)
    report.heading("The film's field, and where the paper's Eq. 1 differs")
    report.text(
        "magdesign's film (`magdesign.fields.film`) is the field of the film's magnetic charges: below an "
        "infinite film with polarization J0 (-sin kx, 0, cos kx), k = 2 pi / T, at depth z below its bottom "
        "face, |B| = J0 (1 - e^(-kd)) e^(-kz) and Bx / Bz = tan(kx). The paper's Eq. 1 prints "
        "M0 (e^(kd) - 1) e^(-kz), which is this field with z measured from the film's top face; with z from "
        f"the bottom face, as the paper states (Fig. 1C caption), it is e^(kd) = {printed / ours:.3f} times too "
        f"large at d = 0.5 mm, T = 6 mm: at the taxel (z = h = 3.5 mm) and J0 = {float(scene.magnetization) / mT:g} mT "
        f"it gives {printed / mT:.3f} mT where the film gives {ours / mT:.3f} mT. Ratios of |B| at two depths, "
        "hence the attenuation distances and the normal read-out of Eq. 3, are the same in both."
    )
    report.text(
        "The study's scene is `examples/film_hall.toml` with the published stack written in (T = 6 mm, "
        f"d = 0.5 mm, h = 3.5 mm, E = 83 kPa, nu = 0.49, Hooke layer, {contact_area(scene) / mm**2:g} mm^2 contact per taxel, 3 x 3 "
        "MLX90393 taxels at 6 mm) and without its effects: the paper's numbers are about the film's own "
        f"field, and the example's background field ({', '.join(load_spec(EXAMPLE)['scene']['background'])}) would "
        f"count as signal. J0 = {float(scene.magnetization) / mT:g} mT is the example's; the paper does not publish "
        "it, and only absolute fields and the design solve's sensitivity target depend on it."
    )

    # --- attenuation --------------------------------------------------------------------
    report.heading("1. Attenuation distances")
    report.text(
        "Definition: the attenuation a at depth z is 1 - |B|(z) / |B|(0), with |B|(0) the field at the film's "
        "bottom face straight above the taxel (the paper: 'compared with the magnetic strength Bmax at "
        "z = 0 mm'); the distance is the depth where a reaches 95, 98, 99 %, found by root-finding on "
        "`film_magnitude` (infinite film) and on `film(..., periods=N)` (a strip N periods wide, exact), at "
        "the strip's centre. For the infinite film the distance is ln(1 / (1 - a)) / k."
    )
    table = [
        [f"{int(100 * a)} %", z / mm, infinite[a] / mm] + [strips[p][a] / mm for p in strips]
        for a, z in ATTENUATION.items()
    ]
    report.table(
        ["attenuation", "published (mm)", "infinite film (mm)"] + [f"{p} period(s) wide (mm)" for p in strips], table
    )

    def rounded(distances):
        return sum(abs(distances[a] - z) <= 0.05 * mm for a, z in ATTENUATION.items())

    between = sum(
        min(infinite[a], strips[3][a]) - 0.05 * mm <= z <= max(infinite[a], strips[3][a]) + 0.05 * mm
        for a, z in ATTENUATION.items()
    )
    report.text(
        "A finite film decays differently at its centre (its edges carry magnetic charges). Within the published "
        f"values' 0.1 mm rounding the infinite film matches {rounded(infinite)} of the {len(ATTENUATION)} distances, "
        f"the 3-period (18 mm) film {rounded(strips[3])} and the single period {rounded(strips[1])}; {between} of the "
        f"{len(ATTENUATION)} published values lie between the infinite and the 3-period film's. The comparison uses "
        "the infinite film, the paper's own model (Eq. 1)."
    )
    attenuation_figure(report, strips)

    # --- trade-off ----------------------------------------------------------------------
    report.heading("2. Sensitivity against range: the balance periods")
    report.text(
        "The paper states that a longer period raises the sensitivity and shortens the range, and gives "
        "balance periods T1 = 5.81 mm (normal) and T2 = 6.24 mm (shear) from its fig. S2, whose definitions "
        "are not in the text. In the model, at fixed h = 3.5 mm, d = 0.5 mm, E = 83 kPa, the trade-off runs "
        "the other way round for the relative read-outs the paper uses: the normal sensitivity "
        "d ln|B| / dP = k h / E (Eq. 2) and the shear sensitivity d angle / dP = k h / G (at rest, equal to "
        "dR_B / dP) both fall as 1 / T, while what bounds the range rises with T: the field left at the "
        "taxel, e^(-kh) of the face value (the paper's 2 % detectability rule), and the shear that turns "
        "the field angle by 90 deg (R_B = tan(kx) single-valued for |kx| < 90 deg, Fig. 1D), G T / 4h. "
        "Our definition of the balance is therefore: **the shortest period (the most sensitive) whose "
        "range still covers the need**: for the normal force, the taxel keeps 2 % of the face field "
        "(T1 = 2 pi h / ln 50); for the shear, the angle stays within 90 deg up to the published 16 kPa. "
        "Both are found by root-finding on the scene's outputs (`field_fraction`, `shear_phase_max`)."
    )
    report.table(
        ["quantity", "published", "magdesign"],
        [
            ["T1 (normal)", f"{BALANCE_NORMAL / mm:.2f} mm", f"{t1 / mm:.3f} mm"],
            ["T2 (shear), nominal G", f"{BALANCE_SHEAR / mm:.2f} mm", f"{t2 / mm:.3f} mm"],
            [
                f"T2 (shear), G = {g_calibrated / kPa:.1f} kPa from the published 0.1 /kPa",
                f"{BALANCE_SHEAR / mm:.2f} mm",
                f"{t2_calibrated / mm:.3f} mm",
            ],
            ["field at the taxel, T = 6 mm, h = 3.5 mm", ">= 2 %", f"{100 * published_design['field_fraction']:.2f} %"],
            [
                "field angle at 16 kPa shear, T = 6 mm (nominal G)",
                "< 90 deg (measured to 16 kPa)",
                f"{published_design['shear_phase_max'] / deg:.1f} deg",
            ],
        ],
    )
    peak = periods[np.argmax(curves["normal_sensitivity"])]
    report.text(
        "If 'sensitivity' means the absolute field change per newton at the taxel (k |B| / k_n, what a Hall "
        "chip of fixed noise resolves), it does rise with T, because e^(-kh) grows; it peaks near "
        f"T = {peak / mm:.1f} mm (on this grid) at h = 3.5 mm, far from the published balance periods, so it "
        "does not give them either."
    )
    report.text(
        f"T1 lands {percent(t1, BALANCE_NORMAL)} from the published value. T2 with the nominal layer "
        f"(G = {g_nominal / kPa:.1f} kPa) lands {percent(t2, BALANCE_SHEAR)} from it: with that G the published "
        f"sensor (T = {PERIOD / mm:g} mm) turns its field angle by {published_design['shear_phase_max'] / deg:.0f} deg "
        f"at {SHEAR_RANGE / kPa:g} kPa, where the paper reads shear up to that load. The paper's own "
        f"small-load shear sensitivity (0.1 /kPa) implies G = k h / 0.1 kPa^-1 = {g_calibrated / kPa:.1f} kPa; "
        f"with it T2 = {t2_calibrated / mm:.2f} mm ({percent(t2_calibrated, BALANCE_SHEAR)}). Caveat: a layer "
        "stiff enough to match the secant 0.1 /kPa over 0..10 kPa (tan(kx) = 1 at 10 kPa) would give a "
        "shorter T2 still; the tan(kx) read-out with a linear layer steepens more than the published "
        "0.27 /kPa above 10 kPa, so this is the model's limit, not a fit."
    )
    trade_off_figure(report, periods, curves, t1, t2, t2_calibrated)
    literal = NORMAL_SENSITIVITY / 100  # 0.01 %/kPa as a fraction of B per pascal
    report.text(
        "Which reading of the published normal sensitivity. The paper defines dB% = |B - B0| / B0 x 100 % "
        "(Eq. 2) and S = d(dB%) / dP, and states S = 0.01 kPa^-1. Taken as a number of percent per kPa, that is "
        f"0.01 %/kPa, {normal_hooke / literal:.0f} times below the model's k h / E = {normal_hooke * kPa:.4f} /kPa. "
        "This study reads it as a fraction of B per kPa, 1 %/kPa, for three reasons. (1) Percent is the "
        "factor 0.01: 'x 100 %' leaves the ratio's value unchanged, and the paper writes S without a percent "
        "sign. (2) The same sentence gives the shear sensitivity, 0.1 kPa^-1, in the same unit, and that one "
        "is of R_B = Bx / Bz, a plain ratio: read so it implies a layer of G = "
        f"{g_calibrated / kPa:.1f} kPa (nominal {g_nominal / kPa:.1f} kPa), where a percent reading would imply "
        f"{100 * g_calibrated / 1e6:.1f} MPa. (3) Eq. 3, P = (c1 E / k h) ln(B / B0), has d ln B / dP = k h / (c1 E): "
        f"the fraction reading needs the compensation coefficient c1 = {normal_hooke / NORMAL_SENSITIVITY:.1f}, "
        f"of the order of the bonded layer's stiffening (the whole face on a bonded layer gives c1 = "
        f"{normal_hooke / bonded:.1f}), where 0.01 %/kPa needs c1 = {normal_hooke / literal:.0f}: a field change "
        f"of at most {100 * literal * NORMAL_RANGE:.1f} % over the published {NORMAL_RANGE / kPa:g} kPa, a film "
        f"that moves {math.log1p(literal * NORMAL_RANGE) / k / 1e-6:.0f} um on the 3.5 mm Ecoflex layer. The "
        "paper's fig. S3, where the number is measured, is not in its text."
    )

    # --- design -------------------------------------------------------------------------
    report.heading("3. Solving (T, h) with the design solver")
    design_table = design_spec["design"]
    report.text(
        "The spec is `examples/film_hall.toml` with the published stack and no effects (above), solved by "
        "`magdesign.spec.design.problem_from_spec` and `magdesign.design.solve`. Its [design] table: "
        f"variables {', '.join(design_table['variables'])}; targets "
        f"{', '.join(f'{k} = {v}' for k, v in design_table['targets'].items())}; limits "
        f"{', '.join(k + ' <= ' + str(v['upper']) for k, v in design_table['limits'].items())}; load sweep normal "
        f"{design_spec['load']['normal']}, shear {design_spec['load']['shear_x']}."
    )
    targets, limit = design_table["targets"], design_table["limits"]["shear_phase_max"]["upper"]
    report.table(
        ["quantity", "solved"],
        [
            ["period T", f"{solved_t / mm:.4f} mm"],
            ["layer thickness h", f"{solved_h / mm:.4f} mm"],
            [f"field_fraction (target {targets['field_fraction']})", f"{result.outputs['field_fraction']:.4f}"],
            [
                f"normal_sensitivity (target {targets['normal_sensitivity']})",
                f"{result.outputs['normal_sensitivity'] / mT:.4f} mT/N",
            ],
            [f"shear_phase_max (limit <= {limit})", f"{result.outputs['shear_phase_max'] / deg:.2f} deg"],
        ],
    )
    dt = result.derivatives["normal_sensitivity"]["magnet.period"]
    report.text(
        f"Status {result.status} in {result.steps} steps. The published target, 2 % of the face field at "
        f"the taxel, fixes h / T = ln 50 / 2 pi = {math.log(50) / (2 * math.pi):.4f} (solved: {solved_h / solved_t:.4f}) "
        "whatever the scale (the paper's "
        "bound h <= 3.8 mm at T = 6 mm); every other published requirement (pressure sensitivities and "
        "ranges) is also a function of k h alone under a Hooke layer, so the published numbers do not fix "
        "T and h separately. The second target, an absolute normal sensitivity, does: it is the example's, "
        "with the example's unpublished J0, so the solved T is not a reproduction of 6 mm. Its implicit "
        f"derivative dT / d(target) = {dt * mT / mm:.2f} mm per mT/N shows how strongly that unpublished "
        "number sets the answer."
    )

    # --- decoupling ---------------------------------------------------------------------
    report.heading("4. Normal / shear decoupling")
    report.text(
        "The paper's decoupling test (Materials and Methods) applies 7 x 7 combinations of normal and "
        "shear displacement in 0.25 mm steps. Here each displacement is turned into the force the layer "
        "needs for it (k_n dZ, k_s dX, Hooke layer) and simulated at the central taxel for the infinite "
        "film and for finite films. The field angle is atan2(Bx, Bz) in the film's frame "
        "(`magdesign.fields.film_angle`), never arctan(Bx / Bz). Eq. 3 is applied with c1 = c2 = 1, "
        "b1 = b2 = 0 (`magdesign.inverse.film_forces`)."
    )
    report.table(
        [
            "film",
            "max \\|B\\| change under shear (relative)",
            "max angle change under normal load (deg)",
            "Eq. 3 RMSE Fz (N)",
            "Eq. 3 RMSE Fx (N)",
            "largest Fz, Fx (N)",
        ],
        [
            [
                "infinite" if p is None else f"{p} period(s), {p * PERIOD / mm:g} mm wide",
                row["magnitude_coupling"],
                row["angle_coupling"] / deg,
                row["rmse_normal"],
                row["rmse_shear"],
                f"{row['max_normal']:.3g}, {row['max_shear']:.3g}",
            ]
            for p, row in rows.items()
        ],
    )
    report.text(
        "Below an infinite film normal load changes only |B| and shear only the angle, so Eq. 3 returns the "
        f"applied forces (largest couplings {ideal['magnitude_coupling']:.1e} and {ideal['angle_coupling'] / deg:.1e} "
        "deg, rounding). A film a few periods wide is not infinite: shear moves its edges relative to the taxel, "
        "so |B| changes with shear and the angle with normal load, and Eq. 3 (an infinite-film formula) errs "
        f"accordingly. Over this grid the 18 mm (3-period) film, the paper's size, changes |B| by "
        f"{100 * coupled['magnitude_coupling']:.0f} % under shear and the angle by {coupled['angle_coupling'] / deg:.1f} "
        "deg under normal load, where the paper measured both constant (Fig. 2G to K): only the ideal film "
        "reproduces its self-decoupling."
    )
    decoupling_figure(report, rows)

    for a in ATTENUATION:
        report.result(f"attenuation_{int(100 * a)}", infinite[a])
        for p in strips:
            report.result(f"attenuation_{int(100 * a)}_periods_{p}", strips[p][a])
    report.result("balance_normal", t1)
    report.result("balance_shear", t2)
    report.result("balance_shear_calibrated", t2_calibrated)
    report.result("shear_modulus_nominal", g_nominal)
    report.result("shear_modulus_calibrated", g_calibrated)
    report.result("normal_pressure_sensitivity_hooke", normal_hooke)
    report.result("normal_pressure_sensitivity_bonded_face", bonded)
    report.result(
        "normal_sensitivity_c1",
        {
            "fraction_reading": normal_hooke / NORMAL_SENSITIVITY,
            "percent_reading": normal_hooke / (NORMAL_SENSITIVITY / 100),
        },
    )
    report.result("shear_pressure_sensitivity", shear_hooke)
    report.result("field_fraction_published_design", published_design["field_fraction"])
    report.result("shear_phase_16kPa_published_design", published_design["shear_phase_max"])
    report.result("eq1_printed_over_corrected", printed / ours)
    report.result(
        "design",
        {
            "status": result.status,
            "period": solved_t,
            "layer_thickness": solved_h,
            "outputs": result.outputs,
            "steps": result.steps,
        },
    )
    report.result(
        "decoupling",
        {
            "infinite" if p is None else f"periods_{p}": {
                key: row[key] for key in ("magnitude_coupling", "angle_coupling", "rmse_normal", "rmse_shear")
            }
            for p, row in rows.items()
        },
    )
    report.write()


if __name__ == "__main__":
    main()
