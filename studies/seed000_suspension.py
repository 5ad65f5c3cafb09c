"""Seed 000: the magnetic-suspension tactile sensor (a Ni-Fe pole in a 4 mm ball over a
magnet plate), magdesign's reduced model against the thesis's FEM numbers.

The scene is examples/pole_plate.toml (PoleScene, PHYSICS.md 1.3). The study computes the
restoring force against tilt, its linear range, the spring coefficient and the field
sensitivities, and sets them beside the thesis's (seeds/000). Full mode adds a finer tilt
grid and the library's own outputs (``spring_coefficient``, ``field_sensitivity``: exact
derivatives at theta = 0) beside the central differences over +-1 mrad that both modes use.

    python studies/seed000_suspension.py [--quick] [--out DIR]
"""

import pathlib
import tomllib

import equinox as eqx
import jax
import jax.numpy as jnp
import matplotlib.pyplot as plt
import numpy as np

from _report import Report, arguments, progress
from magdesign.scene import loads_from_spec, outputs, parameters, scene_from_spec, with_parameters
from magdesign.units import MU0, deg, mm, mT

uN = 1e-6

NAME = "seed000_suspension"
SPEC = pathlib.Path(__file__).resolve().parents[1] / "examples" / "pole_plate.toml"

# Published, seed 000 (master thesis, "magnetic suspension" tactile sensor).
LINEAR_RANGE = 40 * deg  # abstract; Sec. 3.2.2, Fig. 3.5: "linear within the range of +-40 degrees"
# Table 3.1, spring coefficient k. Its unit is lost in the text; read as uN/deg, the unit of
# the initial model's 12.57 uN at 10 deg (Sec. 3.1.1) and of the 1 uN aim (Ch. 5), which over
# k gives a tilt "within the operation range" (Sec. 3.2.2): 1 uN / 0.068 uN/deg = 15 deg.
K_UNIT = uN / deg
K_PM_FULL = 0.068 * K_UNIT  # magnet soleplate, Model 2 (full pole): the modelled sensor
K_PM_HALF = 0.215 * K_UNIT  # magnet soleplate, Model 1 (half pole)
K_NIFE_FULL = 0.215 * K_UNIT  # Ni-Fe soleplate, Model 2
K_NIFE_HALF = 0.639 * K_UNIT  # Ni-Fe soleplate, Model 1
INITIAL_FORCE = 12.57 * uN  # Sec. 3.1.1, Fig. 3.3: initial model, at -10 deg
INITIAL_ANGLE = 10 * deg
SENS_PM = 0.3 * mT / deg  # abstract; Sec. 3.2.4, Fig. 3.9: magnet soleplate, Hall pair at +-0.5 mm
SENS_NIFE = 2.0 * mT / deg  # same: Ni-Fe soleplate, Hall pair at +-1 mm
HALL_X = 0.5 * mm  # the magnet soleplate's pair
HALL_HEIGHT = 0.1 * mm  # Sec. 3.2.3 / Fig. 3.8: the field is read 0.1 mm above the plate
SENS_SPAN = 10 * deg  # Sec. 3.2.4: the difference is taken over a 10 deg turn
GMR_VOLTS_PER_AM = 0.131e-3  # Sec. 4.3, Fig. 4.7: 0.131 mV per A/m at 0.6 V bias

# Tolerances (the thesis states none). The reduced level is asked to agree with the FEM in
# order, within a factor 2; "linear" means within 10 % of k theta; the GMR preset is exact.
FACTOR = 2.0
LINEARITY = 0.10
RANGE_TOLERANCE = 5 * deg
GMR_TOLERANCE = 1e-6
SECANT = 1e-3  # rad: derivatives at 0 as central differences over +-SECANT (relative error ~1e-6)


@eqx.filter_jit
def tilt_sweep(scene, thetas, points):
    """At each tilt (rad): the library's restoring force -F_t (N, per ball radius) and the
    field at ``points`` (T); the plate's vertical pull on the rod at rest (N) and the
    plate's B_z at the rod's tip (T)."""
    force = -jax.vmap(scene.tangential_force)(thetas)
    fields = jax.vmap(lambda t: scene.source_field(points, scene.tip(t) - scene.tip(0.0)))(thetas)
    positions, charges = scene.charges(jnp.zeros(3))
    attraction = -jnp.sum(charges * scene.plate_field(positions)[:, 2]) / MU0
    return force, fields, attraction, scene.plate_field(positions[:1])[0, 2]


def linear_range(thetas, force, k):
    """The first tilt > 0 (rad) where the force leaves k theta +- LINEARITY, interpolated."""
    positive = thetas > 0
    theta, error = thetas[positive], np.abs(force[positive] / (k * thetas[positive]) - 1)
    outside = np.nonzero(error > LINEARITY)[0]
    if outside.size == 0:
        return float(theta[-1])
    i = outside[0]
    if i == 0:
        return float(theta[0])
    return float(np.interp(LINEARITY, error[i - 1 : i + 1], theta[i - 1 : i + 1]))


def row(key, quantity, published, source, magdesign, difference, within, why):
    """A comparison row; ``within`` None for a number the model cannot compute."""
    verdict = "" if within is None else (" (within tolerance)" if within else " (outside tolerance)")
    return {"key": key, "within": within, "quantity": quantity, "published": published, "source": source,
            "magdesign": magdesign, "difference": difference + verdict, "why": why}


def main(argv=None):
    args = arguments(NAME, argv, description=__doc__.splitlines()[0])
    report = Report(NAME, "Seed 000: magnetic suspension, reduced model against the thesis", args.out, args.quick)
    with open(SPEC, "rb") as file:
        spec = tomllib.load(file)
    # with_parameters gives strongly typed leaves where the spec gave weakly typed ones: set
    # them all once, so that the variants below reuse the one compiled sweep
    scene = scene_from_spec(spec)
    scene = with_parameters(scene, parameters(scene))
    p = {key: float(value) for key, value in parameters(scene).items()}

    step = 2.0 if args.quick else 0.25  # deg; exact in binary, so the grid is exactly symmetric about 0
    grid = np.arange(-80 / step, 80 / step + 1) * step * deg
    thetas = jnp.asarray(np.concatenate([grid, [SECANT, -SECANT]]))  # for central differences at 0
    xs = np.linspace(-6 * mm, 6 * mm, 61 if args.quick else 241)
    line = np.stack([xs, 0 * xs, HALL_HEIGHT + 0 * xs], -1)
    probes = np.array([[HALL_X, 0, HALL_HEIGHT], [-HALL_X, 0, HALL_HEIGHT], [p["sensor.offset"], 0, p["sensor.height"]]])
    points = jnp.asarray(np.concatenate([probes, line]))

    progress("tilt sweep: restoring force and field (compiles once)")
    library, fields, attraction, tip_field = (np.asarray(a) for a in tilt_sweep(scene, thetas, points))
    progress("tilt sweep done; the half-length, half-diameter and N_d = 1 variants")
    n = grid.size
    force = library[:n]
    slope = lambda values: float(values[n] - values[n + 1]) / (2 * SECANT)
    k = slope(library)

    # k of a half-length rod (tip to the ball's centre), a half-diameter rod and the most
    # demagnetised rod (N_d = 1): the same program
    variant = lambda values: slope(tilt_sweep(with_parameters(scene, values), thetas, points)[0])  # noqa: E731
    k_half = variant({"pole.length": p["pole.ball_radius"]})
    k_thin = variant({"pole.diameter": p["pole.diameter"] / 2})
    k_flat = variant({"pole.demagnetizing_factor": 1.0})
    progress("variants done")

    at = lambda angle: int(np.argmin(np.abs(grid - angle)))
    i0, i10 = at(0.0), at(SENS_SPAN)
    hall_pair = fields[:n, 0, 2] - fields[:n, 1, 2]
    hall_sens = (hall_pair[i10] - hall_pair[i0]) / SENS_SPAN
    hall_single = (fields[i10, 0, 2] - fields[i0, 0, 2]) / SENS_SPAN
    gmr_sens = slope(fields[:, 2, 0])  # B_a = B_x: the chip frame is the scene's
    lin = linear_range(grid, force, k)
    peak = float(grid[grid > 0][np.argmax(force[grid > 0])])
    at40 = float(np.interp(LINEAR_RANGE, grid, force) / (k * LINEAR_RANGE))
    f10 = float(np.interp(INITIAL_ANGLE, grid, force))
    # The plainest estimate, with no flux gathered by the rod: the plate's own field at the
    # tip pulling on the rod's face, A B^2 / (2 mu0), acting on the lever r_b sin theta
    # (so about that pull per radian, per ball radius)
    area = np.pi * p["pole.diameter"] ** 2 / 4
    plain_pull = float(area * tip_field**2 / (2 * MU0))

    # The GMR preset's reading per A/m of H along its axis, at rest (its own linear law)
    rest = jnp.zeros((1, 1, 3))
    gmr_gain = float(jax.jacfwd(lambda b: scene.transduce(b)[0, 0, 0])(rest)[0, 0, 0]) * MU0

    if not args.quick:
        progress("library outputs: exact derivatives at theta = 0 (second-order compile)")
        exact = {key: float(value) for key, value in eqx.filter_jit(outputs)(scene, loads_from_spec(spec)).items()}
        progress("library outputs done")

    ratio = lambda a, b: f"x{a / b:.3g}"
    inside = lambda a, b: 1 / FACTOR <= abs(a / b) <= FACTOR
    same_trend = (k_half > k) == (K_PM_HALF > K_PM_FULL)
    positive = (grid > 0) & (grid <= LINEAR_RANGE)
    restores = k > 0 and bool(np.all(force[positive] > 0))
    odd = bool(np.max(np.abs(force + force[::-1])) <= 1e-9 * np.max(np.abs(force)))
    not_modelled = ("PoleScene's plate is a permanent magnet under a soft pole; a soft soleplate under a "
                    "magnetised pole needs a permeable plate (image charges), which the reduced model leaves out")
    rows = [
        row("linear_range", "linear range of F(theta), magnet soleplate, full pole", "+-40 deg", "abstract; Sec. 3.2.2, Fig. 3.5",
            f"+-{lin / deg:.1f} deg within {LINEARITY:.0%} of k theta; F peaks at +-{peak / deg:.1f} deg; F(40 deg) = {at40:.2f} k 40 deg",
            f"{(lin - LINEAR_RANGE) / deg:+.1f} deg", abs(lin - LINEAR_RANGE) <= RANGE_TOLERANCE,
            f"tolerance +-{RANGE_TOLERANCE / deg:g} deg. Reduced model: the rod is magnetised only along its own axis (charge ~ B.axis ~ cos theta) "
            "and the tip's pull acts on a lever r_b sin theta, so F ~ sin(2 theta) / 2; the thesis's FEM also has the "
            "rod's transverse magnetisation and the field along the whole rod"),
        row("k_pm_full", "spring coefficient k, magnet soleplate, full pole (Model 2)", "0.068 uN/deg (unit read as uN/deg)",
            "Table 3.1; Sec. 3.2.2", f"{k / K_UNIT:.4g} uN/deg ({k:.3g} N/rad)", ratio(k, K_PM_FULL),
            inside(k, K_PM_FULL),
            f"tolerance x{FACTOR:g}. Reduced model: point charges at the rod's ends, magnetised by the tip's field over "
            f"N_d = {p['pole.demagnetizing_factor']:g}; its vertical pull at rest is {attraction * 1e3:.2g} mN. k scales as "
            f"1 / N_d, and N_d = 1 (the largest) gives {k_flat / K_UNIT:.3g} uN/deg (x{k_flat / K_PM_FULL:.3g}). The thesis's "
            "own prototype differed from its FEM 'in order' (Sec. 4.2)"),
        row("k_pm_half", "spring coefficient k, magnet soleplate, half pole (Model 1)", "0.215 uN/deg", "Table 3.1",
            f"{k_half / K_UNIT:.4g} uN/deg (rod from the tip to the ball's centre)", ratio(k_half, K_PM_HALF),
            inside(k_half, K_PM_HALF), "as the full pole; the half pole's shape (Fig. 2.3a) is not in the text"),
        row("k_half_over_full", "k(half) / k(full), magnet soleplate", f"{K_PM_HALF / K_PM_FULL:.3g}", "Table 3.1",
            f"{k_half / k:.3g} (half length); {k_thin / k:.3g} (half diameter)", ratio(k_half / k, K_PM_HALF / K_PM_FULL),
            inside(k_half / k, K_PM_HALF / K_PM_FULL),
            f"tolerance x{FACTOR:g}. {'Same' if same_trend else 'Opposite'} direction to the thesis: in the reduced model "
            "a shorter rod keeps the same tip charge (same N_d) and loses its upper end's share of the restoring pull, a "
            "thinner rod carries less charge; the FEM's stiffer half pole comes from the flux distribution the model "
            "does not solve for"),
        row("sensitivity_pm", "sensitivity, magnet soleplate, Hall pair at +-0.5 mm, 0.1 mm above the plate", "0.3 mT/deg",
            "abstract; Sec. 3.2.4, Fig. 3.9", f"{abs(hall_sens) / (mT / deg):.3g} mT/deg (dBz pair over 0..10 deg); "
            f"one chip {abs(hall_single) / (mT / deg):.3g} mT/deg", ratio(abs(hall_sens), SENS_PM),
            inside(hall_sens, SENS_PM),
            f"tolerance x{FACTOR:g}. Reduced model: the rod's {p['pole.diameter'] / mm:g} mm face is a point charge "
            f"{(p['geometry.gap'] - HALL_HEIGHT) / mm:.2g} mm above the sensors, whose near field is far more peaked than a "
            f"face's, with the same induced charge as k"),
        row("sensitivity_nife", "sensitivity, Ni-Fe soleplate, Hall pair at +-1 mm", "2 mT/deg", "abstract; Sec. 3.2.4, Fig. 3.9",
            "not modelled", "not compared", None, not_modelled),
        row("k_nife", "spring coefficient k, Ni-Fe soleplate, half / full pole", "0.639 / 0.215 uN/deg", "Table 3.1",
            "not modelled", "not compared", None, not_modelled),
        row("initial_force", "restoring force at 10 deg, initial model", "12.57 uN", "Sec. 3.1.1, Fig. 3.3",
            f"{f10 / uN:.4g} uN (the plate model, not the initial model)", ratio(f10, INITIAL_FORCE), None,
            "different sensor: the initial model (Fe in a 5.5 mm ball over a pole magnet, gap 0.8 mm, magnet size lost) "
            "is not a PoleScene; listed because the example spec's tilt spring (mechanics.spring = "
            f"{p['mechanics.spring']:.3g} N/rad) is this number"),
        row("gmr", "GMR sensitivity (Panasonic meander, 0.6 V bias)", "0.131 mV per A/m", "Sec. 4.3, Fig. 4.7",
            f"{gmr_gain * 1e3:.6g} mV per A/m", f"{gmr_gain / GMR_VOLTS_PER_AM - 1:+.1e}",
            abs(gmr_gain / GMR_VOLTS_PER_AM - 1) <= GMR_TOLERANCE, "tolerance 1e-6: the preset is defined from this number"),
    ]
    report.comparison(rows)

    report.heading("What the reduced model can and cannot say here")
    report.text(
        f"The scene is `examples/pole_plate.toml`: a {2 * p['pole.ball_radius'] / mm:g} mm ball {p['geometry.gap'] / mm:g} mm "
        f"above a magnet plate of radius {p['magnet.radius'] / mm:g} mm and thickness {p['magnet.height'] / mm:g} mm "
        f"(Br = {p['magnet.remanence']:.4g} T = mu0 x 200 kA/m), carrying a {p['pole.diameter'] / mm:g} mm Ni-Fe rod along a "
        f"diameter (the prototype's core, Sec. 4.1; the analysed pole's diameter and the plate's size are lost in the "
        f"text), N_d = {p['pole.demagnetizing_factor']:g}. The thesis's numbers are FEM with mu_r = 1000 (Sec. 3.2.1)."
    )
    report.text(
        f"In absolute terms the reduced model's spring coefficient is x{k / K_PM_FULL:.3g} the thesis's Table 3.1 value "
        f"(under our reading of its lost unit as uN/deg; {'within' if inside(k, K_PM_FULL) else 'outside'} x{FACTOR:g}) "
        f"and x{f10 / INITIAL_FORCE:.3g} the initial model's {INITIAL_FORCE / uN:g} uN at 10 deg; its Hall sensitivity is "
        f"x{abs(hall_sens) / SENS_PM:.3g} the thesis's ({'within' if inside(hall_sens, SENS_PM) else 'outside'} "
        f"x{FACTOR:g}). It gets the half/full pole trend {'right' if same_trend else 'backwards'}. In form: the pull "
        f"{'restores' if restores else 'does not restore'} over +-{LINEAR_RANGE / deg:.0f} deg (k = {k:.3g} N/rad), F "
        f"{'is' if odd else 'is not'} odd in theta, and it rises up to +-{peak / deg:.0f} deg. It is not tuned to match: "
        f"k scales as Br^2 / N_d, and matching "
        f"Table 3.1 would need N_d = {p['pole.demagnetizing_factor'] * k / K_PM_FULL:.3g} (a demagnetising factor is at "
        f"most 1) or Br = {p['magnet.remanence'] * np.sqrt(K_PM_FULL / k) * 1e3:.3g} mT instead of "
        f"{p['magnet.remanence'] * 1e3:.4g} mT. Nor is the gap all the reduced model's: the plainest estimate, the "
        f"plate's own field at the tip ({tip_field / mT:.3g} mT, no flux gathered by the rod) pulling on the rod's "
        f"{area / mm**2:.3g} mm^2 face, A B^2 / (2 mu0) = {plain_pull * 1e3:.3g} mN, acting on the lever r_b sin theta, "
        f"gives k ~ {plain_pull / K_UNIT:.3g} uN/deg, still x{plain_pull / K_PM_FULL:.3g} the Table 3.1 value; and the "
        f"thesis reports that its prototype's restoring force differed from its FEM's 'in order' (Sec. 4.2, Ch. 5). "
        f"Which side the gap lies on is for the method-of-moments level (a later issue) to settle."
    )
    report.text(
        f"The example spec converts a shear load to tilt with the published spring {p['mechanics.spring']:.3g} N/rad "
        f"({INITIAL_FORCE / uN:g} uN at 10 deg), while the same scene's own restoring stiffness is {k:.3g} N/rad: x{k / p['mechanics.spring']:.3g}. "
        f"A simulated sweep of that spec therefore tilts the ball about {k / p['mechanics.spring']:.2g} times further than "
        f"the scene's own magnetics would."
    )

    report.heading("Restoring force against tilt")
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(6.4, 6.4), sharex=True)
    degrees = grid / deg
    top.plot(degrees, force * 1e3, label="reduced model F(theta)")
    top.plot(degrees, k * grid * 1e3, "--", label=f"k theta, k = {k / K_UNIT:.3g} uN/deg")
    top.axvspan(-LINEAR_RANGE / deg, LINEAR_RANGE / deg, color="0.9", label="published linear range +-40 deg")
    top.set_ylim(1.3 * force.min() * 1e3, 1.3 * force.max() * 1e3)
    top.set_ylabel("restoring force per ball radius (mN)")
    top.legend(fontsize=8)
    top.set_title(f"the published k theta ({K_PM_FULL / K_UNIT:g} uN/deg) is x{K_PM_FULL / k:.2g} of the model's", fontsize=9)
    nonzero = grid != 0
    bottom.plot(degrees[nonzero], force[nonzero] / (k * grid[nonzero]), label="F / (k theta)")
    bottom.axhspan(1 - LINEARITY, 1 + LINEARITY, color="0.85", label="within 10 %")
    for sign in (-1, 1):
        bottom.axvline(sign * LINEAR_RANGE / deg, color="k", lw=0.8)
        bottom.axvline(sign * lin / deg, color="C1", lw=0.8, ls=":")
    bottom.set_xlabel("tilt theta (deg)")
    bottom.set_ylabel("F / (k theta)")
    bottom.legend(fontsize=8)
    report.figure(fig, "restoring_force.png",
                  f"Reduced model: restoring force per ball radius (torque / {p['pole.ball_radius'] / mm:g} mm) against tilt, "
                  f"and its ratio to the linear law; black lines: the thesis's +-40 deg, dotted: the model's 10 % range")
    report.table(
        ["tilt (deg)", "F (uN)", "torque (uN mm)", "F / (k theta)"],
        [[a, float(np.interp(a * deg, grid, force)) / uN, float(np.interp(a * deg, grid, force)) * p["pole.ball_radius"] / (uN * mm),
          float(np.interp(a * deg, grid, force)) / (k * a * deg)] for a in (1, 5, 10, 20, 30, 40, 50, 60)],
    )
    if not args.quick:
        report.text(
            f"Full mode: the library's exact outputs at theta = 0 are spring_coefficient = {exact['spring_coefficient']:.6g} N/rad "
            f"(the central difference above: {k:.6g} N/rad, {k / exact['spring_coefficient'] - 1:+.1e}), field_sensitivity = "
            f"{exact['field_sensitivity'] * deg / mT:.6g} mT/deg at the GMR (central difference: {gmr_sens * deg / mT:.6g} mT/deg) and "
            f"attraction = {exact['attraction'] * 1e3:.4g} mN."
        )

    report.heading("Field 0.1 mm above the plate")
    fig, axis = plt.subplots(figsize=(6.4, 3.6))
    for angle in (0, 10, 20, 40):
        axis.plot(xs / mm, fields[at(angle * deg), 3:, 2] / mT, label=f"{angle} deg")
    for x in (-HALL_X, HALL_X):
        axis.axvline(x / mm, color="k", lw=0.8, ls=":")
    axis.set_xlabel("x (mm)")
    axis.set_ylabel("B_z (mT)")
    axis.legend(fontsize=8, title="tilt")
    report.figure(fig, "field_line.png", "Reduced model: B_z along x, 0.1 mm above the plate (as the thesis's Figs. 3.6-3.7), "
                  "for tilts of 0-40 deg; dotted: the Hall pair at +-0.5 mm")
    report.text(
        f"Sensitivities over the first 10 deg: the Hall pair's difference {hall_sens * deg / mT:.3g} mT/deg, one Hall chip at "
        f"+0.5 mm {hall_single * deg / mT:.3g} mT/deg, the example's GMR (B_x at {p['sensor.offset'] / mm:g} mm, "
        f"{p['sensor.height'] / mm:g} mm high; at theta = 0) {gmr_sens * deg / mT:.3g} mT/deg. The thesis's GMR "
        f"alignment value (Sec. 3.2.5) is lost in the text."
    )

    report.result("published", {"linear_range": LINEAR_RANGE, "k_pm_full": K_PM_FULL, "k_pm_half": K_PM_HALF,
                                 "k_nife_full": K_NIFE_FULL, "k_nife_half": K_NIFE_HALF, "initial_force": INITIAL_FORCE,
                                 "sensitivity_pm": SENS_PM, "sensitivity_nife": SENS_NIFE, "gmr_volts_per_am": GMR_VOLTS_PER_AM})
    report.result("tolerance", {"factor": FACTOR, "linearity": LINEARITY, "range": RANGE_TOLERANCE, "gmr": GMR_TOLERANCE})
    report.result("spring_coefficient", k)
    report.result("spring_coefficient_half", k_half)
    report.result("spring_coefficient_half_diameter", k_thin)
    report.result("spring_coefficient_demagnetizing_1", k_flat)
    report.result("spec_spring", p["mechanics.spring"])
    report.result("linear_range", lin)
    report.result("peak_angle", peak)
    report.result("force_ratio_at_40deg", at40)
    report.result("force_at_10deg", f10)
    report.result("hall_pair_sensitivity", hall_sens)
    report.result("hall_single_sensitivity", hall_single)
    report.result("gmr_field_sensitivity", gmr_sens)
    report.result("gmr_volts_per_am", gmr_gain)
    report.result("tilt", grid)
    report.result("restoring_force", force)
    report.result("attraction", attraction)
    report.result("tip_field", tip_field)
    report.result("plain_pull", plain_pull)
    report.result("within_tolerance", {r["key"]: r["within"] for r in rows})
    if not args.quick:
        report.result("library_outputs", exact)
    report.write()


if __name__ == "__main__":
    main()
