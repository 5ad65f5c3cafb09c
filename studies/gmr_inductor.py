"""The GMR-inductor sensor: a disc magnet in a gel layer over four GMR elements and four chip
inductors, after "A Magnetic Type Tactile Sensor by GMR elements and inductors" (a robotics
conference paper; docs/references.md), "the paper" below.

1. The 3-D displacement inverse over the paper's calibration volume (+-2 mm in x, y,
   0..-4 mm in z, Sec. III-B): GMR readings are simulated with the example spec's effects
   (saturation, A/D noise), inverted by magdesign's model-based inverse
   (``magdesign.inverse.invert_displacement``) and by the paper's own reference-point
   method (Sec. II-B, Eqs. 1-2), against the paper's "roughly 5 percent".
2. Slip detection: stick-slip time series through the inductors (EMF = -N dPhi/dt), the
   A/D noise added, the 3-sigma rule on all four inductors (Sec. II-C), against the
   paper's 90 % detection rate and its false-alarm-free Fig. 13.

    python studies/gmr_inductor.py [--quick] [--out DIR]
"""

import pathlib
import tomllib

import jax
import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from _report import Report, arguments, progress  # noqa: E402

from magdesign.inverse import InverseStatus, displacement_grid, forward_readings, invert_displacement  # noqa: E402
from magdesign.scene import Loads, scene_from_spec, simulate  # noqa: E402
from magdesign.transducers import slip_flags  # noqa: E402
from magdesign.units import parse  # noqa: E402

NAME = "gmr_inductor"
PAPER = '"A Magnetic Type Tactile Sensor by GMR elements and inductors"'
SPEC = pathlib.Path(__file__).resolve().parents[1] / "examples" / "gmr_inductor.toml"

# Published (the GMR-inductor paper; its sections, equations and figures)
DISPLACEMENT_ERROR = 0.05  # Sec. III-B on Figs. 8-9: "small errors of roughly 5 percent"
DETECTION_RATE = 0.90  # Sec. III-C: "The detection rate was at 90 percent through repetitive experiments"
REFERENCE_POINTS = 77  # Sec. III-B: 77 reference points (their layout is not given)
XY_RANGE, Z_RANGE = 2e-3, 4e-3  # Sec. III-B, Figs. 8-9: +-2 mm in x, y; 2 and 4 mm down in z
PLANES = (-2e-3, -4e-3)  # Fig. 8 (z = 2 mm) and Fig. 9 (z = 4 mm)
SAMPLE_STEP = 1e-3  # Fig. 13: "time steps of 1 ms"
SMALL_SLIP = 0.1e-3  # Sec. III-C: the third slip of Fig. 13 moved the surface by 0.1 mm

# Our choices (not published)
RESOLUTION = 20e-6  # m: the displacement step the inverse is asked to resolve (1 % of 2 mm)
CANDIDATES = 4  # per axis: the inverse's table of starting points
NORMAL_FORCE = 5.0  # N during the slip tests ("a certain amount of force"; Fig. 10 is at 5 N)
STICK_TIME = 0.2  # s of shear build-up before each slip
RELEASE_TIMES = (1e-3, 2e-3, 5e-3, 1e-2, 2e-2, 5e-2, 0.1, 0.2)  # s, the slip's duration
AMPLITUDES = (SMALL_SLIP, 1e-3)  # m: Fig. 13's smallest slip and a 10x larger one
FAST_RELEASE = (1e-3, 5e-3)  # s: "increases rapidly" in Fig. 13, at its 1 ms steps
ANGLES_DEG = (0.0, 15.0, 30.0, 40.0, 45.0)  # slip direction from the x axis
STATUSES = ("successful", "ill_conditioned", "ambiguous", "no_match", "not_converged")  # InverseStatus's names


def load_scene(quick):
    spec = tomllib.loads(SPEC.read_text())
    if quick:
        spec["magnet"]["fidelity"] = "dipole"  # the cheapest field; full mode uses the exact one
    noise = parse(spec["scene"]["noise"], "V", key="scene.noise")
    return scene_from_spec(spec), noise, spec


def loads_for(scene, displacement, time=None):
    """The loads that move the magnet by ``displacement`` (n, 3) (m) through the scene's layer."""
    stiffness = scene.mechanics.stiffness
    return Loads(-displacement[:, 2] * stiffness.normal, shear=displacement[:, :2] * stiffness.shear, time=time)


def reference_point_inverse(readings, ref_points, ref_readings, gradients):
    """The paper's Sec. II-B: the three reference points nearest in summed |dV| (Eq. 1), each
    linearised with its reading gradients (Eq. 2, four equations in three unknowns, solved
    in the least-squares sense), the three displacements averaged (step 6)."""
    distance = np.abs(readings[:, None, :] - ref_readings[None]).sum(-1)
    nearest = np.argsort(distance, axis=1)[:, :3]
    delta = np.linalg.pinv(gradients[nearest]) @ (readings[:, None, :] - ref_readings[nearest])[..., None]
    return (ref_points[nearest] + delta[..., 0]).mean(axis=1)


def displacement_study(report, scene, noise, quick, key):
    rng = np.random.default_rng(3)
    per_plane = 12 if quick else 50
    planes = np.concatenate(
        [np.column_stack([rng.uniform(-XY_RANGE, XY_RANGE, (per_plane, 2)), np.full(per_plane, z)]) for z in PLANES]
    )
    side = 5 if quick else 9
    xy, zs = np.linspace(-XY_RANGE, XY_RANGE, side), np.linspace(0.0, -Z_RANGE, side)
    volume = np.asarray(displacement_grid(xy, xy, zs))
    truth = np.concatenate([planes, volume])

    progress(f"simulating {len(truth)} noisy GMR readings (effects: {', '.join(e.name for e in scene.effects)})")
    result = simulate(scene, loads_for(scene, truth), key=key)
    assert np.allclose(result.displacement, truth, atol=1e-12)
    readings = np.asarray(result.readings)

    progress("model-based inverse (compiles the forward chain's least squares; ~1 min at the exact level)")
    candidates = displacement_grid(*(np.linspace(-3e-3, 3e-3, CANDIDATES),) * 2, np.linspace(1e-3, -5e-3, CANDIDATES))
    inversion = invert_displacement(
        scene, readings, noise=noise, resolution=RESOLUTION, candidates=candidates, starts=2
    )
    model = np.asarray(inversion.displacement)
    statuses = {name: int(np.sum(inversion.status == getattr(InverseStatus, name))) for name in STATUSES}

    progress("the paper's reference-point method (5 x 5 x 3 noise-free reference readings)")
    ref_axes = (np.linspace(-XY_RANGE, XY_RANGE, 5), np.linspace(-XY_RANGE, XY_RANGE, 5), np.array([0.0, -2e-3, -4e-3]))
    ref_points = np.asarray(displacement_grid(*ref_axes))
    ref_readings = np.asarray(forward_readings(scene, ref_points))[..., 0]
    grid = ref_readings.reshape(*(len(a) for a in ref_axes), -1)
    gradients = np.stack(np.gradient(grid, *ref_axes, axis=(0, 1, 2)), axis=-1).reshape(len(ref_points), -1, 3)
    paper = reference_point_inverse(readings[..., 0], ref_points, ref_readings, gradients)

    def relative(estimate, rows):
        return np.linalg.norm(estimate[rows] - truth[rows], axis=-1) / np.linalg.norm(truth[rows], axis=-1)

    rows = {z: np.flatnonzero(np.isclose(truth[: 2 * per_plane, 2], z)) for z in PLANES}
    error = {
        (method, z): relative(estimate, rows[z])
        for method, estimate in (("model", model), ("paper", paper))
        for z in PLANES
    }
    absolute = {
        method: np.linalg.norm(estimate[2 * per_plane :] - volume, axis=-1)
        for method, estimate in (("model", model), ("paper", paper))
    }
    sigma = float(np.median(np.linalg.norm(np.asarray(inversion.uncertainty)[2 * per_plane :], axis=-1)))

    for (method, z), values in error.items():
        tag = f"{method}_z{abs(z) * 1e3:.0f}mm"
        report.result(f"relative_error_median_{tag}", float(np.median(values)))
        report.result(f"relative_error_p95_{tag}", float(np.percentile(values, 95)))
        report.result(f"relative_error_max_{tag}", float(values.max()))
    for method, values in absolute.items():
        report.result(f"volume_error_median_{method}", float(np.median(values)))
        report.result(f"volume_error_p95_{method}", float(np.percentile(values, 95)))
        report.result(f"volume_error_max_{method}", float(values.max()))
    report.result("inverse_status_counts", statuses)
    report.result("inverse_uncertainty_median", sigma)
    report.result("reference_points", len(ref_points))
    return dict(
        error=error,
        absolute=absolute,
        statuses=statuses,
        volume=volume,
        per_plane=per_plane,
        ref_axes=ref_axes,
        side=side,
        sigma=sigma,
    )


def slip_events(quick, rng):
    """The event list: (amplitude (m), release time (s), angle (rad), group)."""
    repeats = 6 if quick else 40
    events = [(d, t, 0.0, "speed") for d in AMPLITUDES for t in RELEASE_TIMES for _ in range(repeats)]
    # the Fig. 13-like population: log-uniform 0.1..1 mm, released in 1..5 ms, along x
    population = 30 if quick else 200
    size = np.exp(rng.uniform(np.log(SMALL_SLIP), np.log(AMPLITUDES[-1]), population))
    events += [(d, t, 0.0, "population") for d, t in zip(size, rng.uniform(*FAST_RELEASE, population))]
    events += [(0.3e-3, 2e-3, np.radians(a), "angle") for a in ANGLES_DEG for _ in range(repeats)]
    # three population slips open the record (drawn in Fig. 13 style), the rest shuffled after them
    first = len(AMPLITUDES) * len(RELEASE_TIMES) * repeats
    rest = [i for i in range(len(events)) if not first <= i < first + 3]
    return events[first : first + 3] + [events[i] for i in rng.permutation(rest)]


def slip_series(events, rng):
    """Magnet displacement (n, 2) (m) at the 1 kHz samples and each release's sample span.

    Each event: the shear displacement builds up linearly from 0 to d along its direction
    for STICK_TIME (plus a random fraction of a sample, so releases start anywhere between
    samples), then returns to 0 linearly in the release time (the slip); the next stick
    starts at once, after a 30 ms pause at rest."""
    knots_t, knots_u, spans, start = [0.0], [np.zeros(2)], [], 0.05
    for d, release, angle, _ in events:
        direction = np.array([np.cos(angle), np.sin(angle)])
        top = start + STICK_TIME + rng.uniform(0.0, SAMPLE_STEP)
        knots_t += [start, top, top + release]
        knots_u += [np.zeros(2), d * direction, np.zeros(2)]
        spans.append((int(np.floor(top / SAMPLE_STEP)), int(np.ceil((top + release) / SAMPLE_STEP))))
        start = top + release + 0.03
    time = np.arange(0.0, start + 0.05, SAMPLE_STEP)
    knots_u = np.array(knots_u)
    u = np.column_stack([np.interp(time, knots_t, knots_u[:, i]) for i in range(2)])
    return time, u, np.array(spans)


def score(flags, spans):
    """Per event: detected (a flag from one sample before the release to two after it);
    false alarms: flagged runs that start outside every release."""
    flags = np.asarray(flags)
    inside = np.zeros(flags.shape, bool)
    detected = np.zeros(len(spans), bool)
    for k, (a, b) in enumerate(spans):
        window = slice(max(a - 1, 0), b + 3)
        inside[window] = True
        detected[k] = flags[window].any()
    run_starts = flags & ~np.concatenate([[False], flags[:-1]])
    return detected, int(np.sum(run_starts & ~inside))


def slip_study(report, scene, noise, quick, key):
    rng = np.random.default_rng(13)
    events = slip_events(quick, rng)
    time, u, spans = slip_series(events, rng)
    displacement = np.column_stack([u, np.full(len(time), -NORMAL_FORCE / float(scene.mechanics.stiffness.normal))])
    progress(f"simulating {len(events)} stick-slip events ({len(time)} samples at 1 kHz) through the inductors")
    loads = loads_for(scene, displacement, time)
    result = simulate(scene, loads, key=key)
    # the inductors' outputs carry the spec's inductors.noise (the same A/D board as the
    # GMR readings, Sec. III-A), drawn by simulate from its key; their flags are the scene's
    output = np.asarray(result.extras["inductor_emf"])
    window = scene.inductors.window
    flags = np.asarray(result.extras["slip"])
    detected, false_alarms = score(flags, spans)
    single = [score(slip_flags(output[:, c], window=window), spans) for c in range(output.shape[1])]
    minutes = time[-1] / 60.0

    group = np.array([e[3] for e in events])
    amplitude, release, angle = (np.array([e[i] for e in events]) for i in range(3))
    population = group == "population"
    small = population & (amplitude < 2 * SMALL_SLIP)
    rate = {
        (d, t): detected[(group == "speed") & (amplitude == d) & (release == t)].mean()
        for d in AMPLITUDES
        for t in RELEASE_TIMES
    }
    by_angle = {a: detected[(group == "angle") & np.isclose(angle, np.radians(a))].mean() for a in ANGLES_DEG}
    # the slowest slip speed (d / release time) still detected 90 % of the time, per amplitude
    threshold = {}
    for d in AMPLITUDES:
        speeds = np.array([d / t for t in RELEASE_TIMES])
        ok = np.array([rate[(d, t)] >= DETECTION_RATE for t in RELEASE_TIMES])
        threshold[d] = float(speeds[ok].min()) if ok.any() else float("nan")
    # the weakest of the four inductors' peak |EMF| during each release, its smallest over the population
    clean = np.asarray(simulate(scene, loads, without=("noise",)).extras["inductor_emf"])
    weakest = [np.abs(clean[a - 1 : b + 2]).max(axis=0).min() for a, b in spans[population]]

    report.result("slip_events", len(events))
    report.result("slip_record_seconds", float(time[-1]))
    report.result("slip_detection_rate_population", float(detected[population].mean()))
    report.result("slip_detection_rate_population_small", float(detected[small].mean()) if small.any() else None)
    report.result("slip_false_alarms", false_alarms)
    report.result("slip_false_alarms_per_minute", false_alarms / minutes)
    report.result("slip_single_inductor_detection_rate", [float(s[0][population].mean()) for s in single])
    report.result("slip_single_inductor_false_alarms_per_minute", [s[1] / minutes for s in single])
    report.result(
        "slip_detection_rate_by_speed", {f"{d * 1e3:g}mm_{t * 1e3:g}ms": float(r) for (d, t), r in rate.items()}
    )
    report.result("slip_detection_rate_by_angle", {f"{a:g}deg": float(r) for a, r in by_angle.items()})
    report.result("slip_speed_for_90_percent", {f"{d * 1e3:g}mm": v for d, v in threshold.items()})
    report.result("inductor_noise", float(scene.inductors.noise))
    return dict(
        time=time,
        u=u,
        output=output,
        flags=np.asarray(flags),
        spans=spans,
        events=events,
        detected=detected,
        false_alarms=false_alarms,
        single=single,
        minutes=minutes,
        rate=rate,
        by_angle=by_angle,
        threshold=threshold,
        population=population,
        small=small,
        weakest=min(weakest),
        window=window,
    )


def percent(x):
    return f"{100 * x:.2f} %"


def main(argv=None):
    args = arguments(NAME, argv, __doc__)
    report = Report(
        NAME, f"GMR-inductor sensor: displacement inverse and slip detection ({PAPER})", args.out, args.quick
    )
    scene, noise, spec = load_scene(args.quick)
    fidelity = spec["magnet"].get("fidelity", "exact")
    key_gmr, key_slip = jax.random.split(jax.random.key(3))
    d = displacement_study(report, scene, noise, args.quick, key_gmr)
    s = slip_study(report, scene, noise, args.quick, key_slip)
    progress("writing the report")

    model_why = (
        "readings simulated by the same model the inverse inverts, with the spec's A/D noise only "
        f"({noise * 1e3:g} mV, about {d['sigma'] * 1e6:.1f} um of displacement): "
        "no gel hysteresis or creep, no magnet tilt, no GMR placement error, no Earth field, all of which "
        "the bench has; this is the noise floor of the chain"
    )
    references = int(np.prod([len(a) for a in d["ref_axes"]]))
    step_xy, step_z = (float(abs(np.diff(d["ref_axes"][i])[0])) for i in (0, 2))
    rows = []
    for z, figure in zip(PLANES, ("Fig. 8", "Fig. 9")):
        model, paper = d["error"][("model", z)], d["error"][("paper", z)]
        rows.append(
            dict(
                quantity=f"displacement error, z = {abs(z) * 1e3:.0f} mm plane, magdesign inverse",
                published="roughly 5 %",
                source=f"Sec. III-B, {figure}",
                magdesign=f"median {percent(np.median(model))}, 95th pct {percent(np.percentile(model, 95))}",
                difference=f"{100 * (np.median(model) - DISPLACEMENT_ERROR):+.2f} points (median)",
                why=model_why,
            )
        )
        rows.append(
            dict(
                quantity=f"displacement error, z = {abs(z) * 1e3:.0f} mm plane, the paper's reference-point method on the same readings",
                published="roughly 5 %",
                source=f"Sec. II-B Eqs. 1-2, Sec. III-B, {figure}",
                magdesign=f"median {percent(np.median(paper))}, 95th pct {percent(np.percentile(paper, 95))}",
                difference=f"{100 * (np.median(paper) - DISPLACEMENT_ERROR):+.2f} points (median)",
                why=f"the same noise plus the method's interpolation error between {references} reference points "
                f"{step_xy * 1e3:g} mm (x, y) and {step_z * 1e3:g} mm (z) apart (the paper's {REFERENCE_POINTS} "
                "points' layout is not published); the bench effects above are absent. So the method itself "
                "accounts for only this much of the paper's 5 %: the rest is the bench's",
            )
        )
    pop = s["detected"][s["population"]]
    rows.append(
        dict(
            quantity="slip detection rate, 3 sigma on all four inductors",
            published="90 %",
            source="Sec. III-C",
            magdesign=f"{percent(pop.mean())} of {pop.size} slips ({SMALL_SLIP * 1e3:g}-{AMPLITUDES[-1] * 1e3:g} mm along x, "
            f"released in {FAST_RELEASE[0] * 1e3:g}-{FAST_RELEASE[1] * 1e3:g} ms)",
            difference=f"{100 * (pop.mean() - DETECTION_RATE):+.1f} points",
            why="event model: the paper gives no slip sizes or speeds beyond Fig. 13; misses here come from noise alone, "
            f"and in these fast slips every inductor peaks at {s['weakest'] * 1e3:.0f} mV or more against "
            f"{noise * 1e3:g} mV of noise. The rate falls below 90 % for slower slips "
            f"(below {s['threshold'][SMALL_SLIP] * 1e3:.3g} mm/s for 0.1 mm slips, table below) and for slips along a "
            f"diagonal of the inductor square (45 deg: {percent(s['by_angle'][45.0])}, table below)",
        )
    )
    small = s["detected"][s["small"]]
    rows.append(
        dict(
            quantity="smallest slip of Fig. 13 (0.1 mm) detected",
            published="detected",
            source="Sec. III-C, Fig. 13",
            magdesign=(
                f"{percent(small.mean())} of {small.size} slips of {SMALL_SLIP * 1e3:g}-{2 * SMALL_SLIP * 1e3:g} mm"
                if small.size
                else "no such event drawn"
            ),
            difference="none"
            if small.size and small.mean() == 1.0
            else f"{percent(1 - small.mean())} missed"
            if small.size
            else "-",
            why=("as published" if small.size and small.mean() == 1.0 else "not all detected")
            + ": the event model as above (fast releases)",
        )
    )
    per_sample = np.mean([x[1] for x in s["single"]]) / len(s["time"])
    rows.append(
        dict(
            quantity="false alarms of the all-four rule",
            published="none (slips flagged only at the three slip moments)",
            source="Sec. III-C, Fig. 13",
            magdesign=f"{s['false_alarms']} in {s['minutes']:.1f} min",
            difference=f"{s['false_alarms']}",
            why=f"{'as published' if s['false_alarms'] == 0 else 'not as published'}: one inductor alone leaves its band "
            f"on noise at {per_sample:.2g} of the samples (run starts), "
            f"four independent ones together at about its 4th power, {per_sample**4:.0e} (Gaussian A/D noise; "
            "vibration of the bench is not modelled)",
        )
    )
    report.comparison(rows)

    report.text(
        f"Scene: `examples/gmr_inductor.toml` (field fidelity **{fidelity}**). The paper gives neither the gel's "
        f"thickness nor the coordinates of Fig. 4, so the magnet height ({spec['geometry']['gap']} over the substrate), "
        f"the GMRs' positions ({', '.join('(' + ', '.join(q[:2]) + ')' for q in spec['sensor']['positions'])}) and the "
        f"inductors' ({', '.join('(' + ', '.join(q[:2]) + ')' for q in spec['inductors']['positions'])}) are the "
        "example's choices; the GMR readings carry the spec's effects "
        f"({', '.join(e.name for e in scene.effects)}; noise {noise * 1e3:g} mV, the 12-bit A/D's quantisation noise). "
        "Every magdesign number below is computed by this run."
    )

    report.heading("1. Displacement inverse over the calibration volume")
    report.text(
        f"Test displacements: {d['per_plane']} random (x, y) in +-2 mm on each of the planes z = -2 mm (Fig. 8) and "
        f"z = -4 mm (Fig. 9), and a {d['side']} x {d['side']} x {d['side']} grid over the whole volume (x, y in "
        "+-2 mm, z from 0 to -4 mm). Each is pushed through the layer (`simulate`, with noise) and inverted twice: by "
        "`magdesign.inverse.invert_displacement` (least squares on the forward chain, started from the two nearest of "
        f"a {CANDIDATES} x {CANDIDATES} x {CANDIDATES} candidate table, resolution {RESOLUTION * 1e6:g} um), and by the "
        "paper's method (Sec. II-B): the "
        "three reference points nearest in summed |dV| (Eq. 1), each linearised with the reference readings' "
        "gradients (central differences over the reference grid) and solved in the least-squares sense (Eq. 2), the "
        f"three results averaged. Its reference grid is {' x '.join(str(len(a)) for a in d['ref_axes'])} = {references} "
        f"points (x, y at {step_xy * 1e3:g} mm, z = {', '.join(f'{z * 1e3:g}' for z in d['ref_axes'][2])} mm), "
        f"noise-free (averaged calibration readings), against the paper's {REFERENCE_POINTS}. "
        "Relative error = |u_est - u| / |u| (|u| >= 2 mm on these planes)."
    )
    table = []
    for (method, z), values in d["error"].items():
        label = "magdesign inverse" if method == "model" else "paper's method"
        table.append(
            [
                label,
                f"{z * 1e3:g}",
                percent(np.median(values)),
                percent(np.percentile(values, 95)),
                percent(values.max()),
            ]
        )
    report.table(["method", "plane z (mm)", "median", "95th percentile", "max"], table)
    report.text("Absolute error over the whole volume grid (um):")
    report.table(
        ["method", "median", "95th percentile", "max"],
        [
            [
                "magdesign inverse" if m == "model" else "paper's method",
                np.median(v) * 1e6,
                np.percentile(v, 95) * 1e6,
                v.max() * 1e6,
            ]
            for m, v in d["absolute"].items()
        ],
    )
    on_reference = np.isclose(d["volume"][:, 2][:, None], d["ref_axes"][2][None]).any(axis=1)
    on_planes, between = d["absolute"]["paper"][on_reference], d["absolute"]["paper"][~on_reference]
    report.text(
        "Inverse status over all test readings: "
        + ", ".join(f"{name} {count}" for name, count in d["statuses"].items())
        + ". The inverse's own standard deviation (from the Jacobian and the noise) is "
        f"{d['sigma'] * 1e6:.2f} um (median over the grid), against its median error of "
        f"{np.median(d['absolute']['model']) * 1e6:.2f} um above. The paper's method adds its interpolation error: over "
        f"the grid its median error is {np.median(on_planes) * 1e6:.1f} um on the reference planes and "
        f"{np.median(between) * 1e6:.1f} um between them."
    )
    report.figure(
        inverse_figure(d),
        "inverse.png",
        "Left: relative error on the Fig. 8 and Fig. 9 planes, both methods. "
        "Right: absolute error over the volume grid against depth.",
    )

    report.heading("2. Slip detection by the inductors")
    report.text(
        f"Event model (ours; the paper publishes only Fig. 13): a constant {NORMAL_FORCE:g} N press; in each event the shear "
        f"displacement of the magnet builds up linearly from 0 to d over {STICK_TIME * 1e3:g} ms (stick), then returns "
        "to 0 linearly in the release time (slip), starting anywhere between two samples; 30 ms at rest, then the "
        "next event. The magnet follows the layer (`Loads` through the spec's Hooke layer). Sampling 1 kHz (Fig. 13). "
        f"Inductor output = {float(scene.inductors.amplification):g} x (-N d(Bz A)/dt), N = "
        f"{float(scene.inductors.turns):g}, from `simulate`, with Gaussian A/D noise of "
        f"{float(scene.inductors.noise) * 1e3:g} mV (the spec's `inductors.noise`, the same board as the GMR readings). "
        f"Rule: the scene's slip flags (`magdesign.transducers.slip_flags`), mean +- 3 sigma over the last {s['window']} samples "
        "(the spec's window; the paper's N is not given), a slip where all four inductors are outside at once. "
        "A slip counts as detected if a flag falls between one sample before its release and two samples after it; "
        "every other flagged run is a false alarm. All events are shuffled into one record of "
        f"{s['minutes']:.1f} min: {len(s['events'])} events."
    )
    report.text("Detection rate against the slip's speed (along x):")
    report.table(
        ["release time (ms)"]
        + [f"d = {d_ * 1e3:g} mm: speed (mm/s)" for d_ in AMPLITUDES]
        + [f"d = {d_ * 1e3:g} mm: rate" for d_ in AMPLITUDES],
        [
            [t * 1e3] + [d_ / t * 1e3 for d_ in AMPLITUDES] + [percent(s["rate"][(d_, t)]) for d_ in AMPLITUDES]
            for t in RELEASE_TIMES
        ],
    )
    thresholds = list(s["threshold"].values())
    same = max(thresholds) <= 2.5 * min(thresholds)  # within one step of the release-time grid
    report.text(
        "The slowest slip detected at least 90 % of the time moves at "
        + ", ".join(f"{v * 1e3:.3g} mm/s for d = {d_ * 1e3:g} mm" for d_, v in s["threshold"].items())
        + (
            ". The threshold is a speed, not a size: the EMF is proportional to the rate of change of flux. "
            "Slips released over tens of milliseconds would therefore give misses like the bench's 10 %; "
            "Fig. 13 does not show how fast its slips were released."
            if same
            else ". The two thresholds differ by more than one step of the release-time grid."
        )
    )
    report.text("Detection rate against the slip's direction (d = 0.3 mm released in 2 ms):")
    report.table(["angle from x (deg)", "rate"], [[a, percent(r)] for a, r in s["by_angle"].items()])
    diagonal = s["by_angle"][45.0]
    report.text(
        f"Along a diagonal of the inductor square (45 deg, detected {percent(diagonal)}) the two inductors on the other "
        "diagonal sit at equal distances from the moving magnet on either side of its path, so their flux does not "
        "change to first order and the all-four rule "
        + ("cannot fire: a blind direction of this layout" if diagonal == 0 else "barely fires")
        + " (the example's square; Fig. 4's coordinates are not in the text)."
    )
    single_rates = [float(x[0][s["population"]].mean()) for x in s["single"]]
    report.text(
        "Each inductor alone (the same 3-sigma band) detects "
        + ", ".join(percent(r) for r in single_rates)
        + " of the population's slips but raises "
        + ", ".join(f"{x[1] / s['minutes']:.0f}" for x in s["single"])
        + f" false alarms per minute; the all-four rule raises {s['false_alarms']} in the whole record: why the "
        "paper requires all four (Sec. III-C, 'robustness to partial slips')."
    )
    report.figure(
        slip_figure(s),
        "slip.png",
        "Top: a stretch of the record (magnet shear displacement, four inductor "
        "outputs, all-four flags) as in Fig. 13. Bottom: detection rate against slip speed and direction.",
    )
    report.result("field_fidelity", fidelity)
    report.write()


def inverse_figure(d):
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4))
    bins = np.logspace(-4, 0, 41)
    for (method, z), values in d["error"].items():
        label = f"{'magdesign' if method == 'model' else 'paper method'}, z = {z * 1e3:g} mm"
        left.hist(np.maximum(values, 1e-4), bins=bins, histtype="step", label=label)
    left.axvline(DISPLACEMENT_ERROR, color="k", ls="--", label="published ~5 %")
    left.set(xscale="log", xlabel="relative displacement error", ylabel="test points")
    left.legend(fontsize=8)
    depth = -d["volume"][:, 2] * 1e3
    for method, marker in (("model", "o"), ("paper", "x")):
        right.scatter(
            depth,
            d["absolute"][method] * 1e6,
            s=8,
            marker=marker,
            label="magdesign inverse" if method == "model" else "paper's method",
        )
    right.set(yscale="log", xlabel="depth -z (mm)", ylabel="|error| (um)")
    right.legend(fontsize=8)
    return fig


def slip_figure(s):
    fig, axes = plt.subplots(2, 2, figsize=(11, 7), gridspec_kw=dict(height_ratios=[1.2, 1]))
    top = fig.add_subplot(2, 1, 1)
    axes[0, 0].remove()
    axes[0, 1].remove()
    # the record's first three events (population slips), as in Fig. 13
    a, b = 0, s["spans"][2][1] + 40
    t = s["time"][a:b]
    for c in range(4):
        top.plot(t, s["output"][a:b, c] * 1e3, lw=0.7, label=f"inductor {c + 1}")
    flagged = t[s["flags"][a:b]]
    top.plot(flagged, np.full(flagged.shape, top.get_ylim()[1]), "kv", label="slip (all four)")
    twin = top.twinx()
    twin.plot(t, np.linalg.norm(s["u"][a:b], axis=1) * 1e3, "k", lw=1.2)
    twin.set_ylabel("shear displacement (mm)")
    top.set(xlabel="time (s)", ylabel="inductor output (mV)")
    top.legend(fontsize=7, loc="lower left", ncol=5)
    for d in AMPLITUDES:
        speeds = [d / t_ * 1e3 for t_ in RELEASE_TIMES]
        axes[1, 0].plot(speeds, [s["rate"][(d, t_)] for t_ in RELEASE_TIMES], "o-", label=f"d = {d * 1e3:g} mm")
    axes[1, 0].axhline(DETECTION_RATE, color="k", ls="--", label="published 90 %")
    axes[1, 0].set(xscale="log", xlabel="slip speed (mm/s)", ylabel="detection rate")
    axes[1, 0].legend(fontsize=8)
    axes[1, 1].plot(list(s["by_angle"]), list(s["by_angle"].values()), "o-")
    axes[1, 1].set(xlabel="slip direction from x (deg)", ylabel="detection rate", ylim=(-0.05, 1.05))
    fig.tight_layout()
    return fig


if __name__ == "__main__":
    main()
