"""The dome-Hall sensor: a hemispherical Mooney-Rivlin dome carries an N35 magnet over an
AK8963 Hall chip.

The paper, "Design and Fabrication of a Soft Magnetic Tactile Sensor" (docs/references.md),
against magdesign, in five parts:

1. the saturation distance: Eq. 1's closed form and the exact cylinder field on the axis;
2. the dome's force-travel curve at each fidelity level against the published 1.6 mm at 5 N;
3. the default design (rest gap, wall thickness) solved at the Reissner level and confirmed
   at the axisymmetric level, as ``magdesign solve --fidelity auto`` does, with the time of each;
4. the viscoelastic lag of Eq. 2 on the reading over the ramps of Table I;
5. a model-based force inverse (magdesign.inverse) on simulated AK8963 readings against the
   paper's MLP.

    python studies/dome_hall.py [--quick] [--out DIR]

``--quick`` skips the axisymmetric dome (its programs compile for minutes) and inverts the two
test ramps only.
"""

import copy
import time

import jax
import jax.numpy as jnp
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from _report import Report, arguments, number, progress  # noqa: E402

import magdesign  # noqa: E402,F401  (turns on float64)
from magdesign.design import solve  # noqa: E402
from magdesign.fields import cylinder, cylinder_axial  # noqa: E402
from magdesign.inverse import InverseStatus, displacement_grid, invert_displacement  # noqa: E402
from magdesign.mechanics import MooneyRivlin, dome_compliance, dome_curve, lag_pole, time_constant_from_pole  # noqa: E402
from magdesign.scene import Loads, scene_from_spec, simulate  # noqa: E402
from magdesign.spec.design import default_spec, exact_levels, fidelity_levels, problem_from_spec  # noqa: E402
from magdesign.units import mm, mT, uT  # noqa: E402

NAME = "dome_hall"
PAPER = '"Design and Fabrication of a Soft Magnetic Tactile Sensor"'

# Published numbers (the dome-Hall paper; its sections, equations, figures and tables).
RADIUS = 1.5 * mm  # Sec. II.A, Eq. 1: N35 cylinder 3 mm x 1 mm
HEIGHT = 1.0 * mm  # Sec. II.A
REMANENCE = 1.17  # T, Sec. II.A
SATURATION = 4.8 * mT  # Sec. II.A: the AK8963 saturates at 4.8 mT
PAPER_SATURATION_DISTANCE = 6.0 * mm  # Sec. II.A: Eq. 1 "solved ... The corresponding z is obtained 6 mm"
PAPER_MARGIN = 6.4 * mm  # Sec. II.A, Fig. 3: "keeping a distance of 6.4 mm provides a safe margin"
MAX_FORCE = 5.0  # N, Sec. II.B: force specification
TRAVEL = 1.6 * mm  # Sec. II.B: desirable displacement range at 5 N
COMPLIANCE = 0.32 * mm  # m/N, Sec. II.B: "the required compliance is about 0.32 mm/N"
OUTER_RADIUS = 8.0 * mm  # Sec. II.B: the dome that meets it (FEM and experiment, Fig. 6)
THICKNESS = 2.0 * mm  # Sec. II.B
C10, C01 = 0.1182e6, 0.1769e6  # Pa, Sec. II.B: Mooney-Rivlin fit of the tensile test (Fig. 4)
POLE = 0.9804  # Eq. 2 (Sec. V): G(z) = 0.01955 / (1 - 0.9804 z^-1)
SAMPLE_RATE = 100.0  # Hz, Sec. III: the sensor's output is sampled at 100 Hz
TRAIN_RAMPS = (0.1, 0.2, 0.3, 0.4, 0.6, 0.7, 0.8, 0.025, 0.075)  # N/s, Table I
TEST_RAMPS = {"moderate": 0.05, "steep": 0.5}  # N/s, Table I ("one steep and one moderate slope")
MLP_MAE_TRAIN, MLP_MAE_TEST = 0.175, 0.201  # N, Sec. IV
MLP_MAX_STEEP, MLP_MAX_MODERATE = 0.223, 0.247  # N, Sec. V (maximum absolute errors)
MODERATE_SHARE_WITHIN_10 = 0.95  # Sec. V, Fig. 12: "more than 95 percent ... deviate less than 10 percent"
STEEP_DEVIATION_95 = 0.25  # Sec. V, Fig. 12: steep data "more than 25 percent for the same fraction"
STEEP_DEVIATION_ALL = 0.38  # Sec. V, Fig. 12: "At the deviation of 38 percent, all the points ... are covered"

RESIN = MooneyRivlin(c10=C10, c01=C01)
# Tolerances this study holds magdesign to (the why column names them).
SATURATION_TOLERANCE = 0.5 * mm  # the paper rounds Eq. 1's root to whole millimetres
DOME_TOLERANCE = 0.10  # "about 0.32 mm/N", FEM and experiment compared only in a figure (Fig. 6)
HOLD = 5.0  # s after the slowest ramp reaches 5 N (10 time constants): the reading settles


def percent(value):
    return f"{100 * value:+.1f} %"


def mm_text(value, digits=4):
    return f"{number(value / mm, digits)} mm"


def bisect(function, low, high, steps=64):
    """The root of a function that falls through zero between low and high."""
    for _ in range(steps):
        middle = 0.5 * (low + high)
        if function(middle) > 0:
            low = middle
        else:
            high = middle
    return 0.5 * (low + high)


def on_axis(z, fidelity="exact"):
    """B_z (T) of ``fields.cylinder`` on the axis, z (m) above the top face (any shape)."""
    z = jnp.asarray(z, dtype=float)
    points = jnp.stack([jnp.zeros_like(z), jnp.zeros_like(z), HEIGHT / 2 + z], axis=-1)
    return cylinder(points, radius=RADIUS, height=HEIGHT, polarization=REMANENCE, fidelity=fidelity)[..., 2]


def eq1(z):
    """Eq. 1, the closed form of B_z (T) on the axis, z (m) above the top face (the paper's
    coordinate; ``fields.cylinder_axial`` measures from the magnet's centre)."""
    return cylinder_axial(HEIGHT / 2 + z, radius=RADIUS, height=HEIGHT, polarization=REMANENCE)


def saturation_distance(report):
    """Part 1: where the on-axis field falls to the AK8963's 4.8 mT."""
    progress("saturation distance")
    closed_form = jax.jit(eq1)
    exact_field = jax.jit(on_axis)
    dipole_field = jax.jit(lambda z: on_axis(z, "dipole"))
    closed, exact, dipole = (
        bisect(lambda z: float(f(z)) - SATURATION, 1 * mm, 20 * mm) for f in (closed_form, exact_field, dipole_field)
    )
    at_six = float(eq1(PAPER_SATURATION_DISTANCE))
    at_margin = float(eq1(PAPER_MARGIN))
    z = np.linspace(2 * mm, 12 * mm, 201)
    curves = {
        "Eq. 1 (closed form)": np.asarray(eq1(z)),
        "exact cylinder field": np.asarray(on_axis(z)),
        "dipole": np.asarray(on_axis(z, "dipole")),
    }
    for key, value in {
        "saturation_distance_closed_form": closed,
        "saturation_distance_exact": exact,
        "saturation_distance_dipole": dipole,
        "field_at_6mm": at_six,
        "field_at_margin": at_margin,
    }.items():
        report.result(key, value)
    return dict(closed=closed, exact=exact, dipole=dipole, at_six=at_six, at_margin=at_margin, z=z, curves=curves)


def dome_levels(report, quick):
    """Part 2: the force-travel curve of the paper's dome at each level."""
    progress("dome: Reissner closed forms")
    reissner = float(
        dome_compliance(
            outer_radius=OUTER_RADIUS, thickness=THICKNESS, material=RESIN, max_force=MAX_FORCE, fidelity="reissner"
        )
    )
    # Reissner's formula with the outer radius as its shell radius (the library takes the
    # mid-surface radius R_o - t/2): a dome of outer radius R_o + t/2 has mid-surface R_o.
    reissner_outer = float(
        dome_compliance(
            outer_radius=OUTER_RADIUS + THICKNESS / 2,
            thickness=THICKNESS,
            material=RESIN,
            max_force=MAX_FORCE,
            fidelity="reissner",
        )
    )
    levels = {"reissner": reissner, "reissner_outer": reissner_outer}
    curve = sliding = None
    seconds = {}
    if not quick:
        progress("dome: axisymmetric force-travel path to 5 N (the first call compiles)")
        start = time.perf_counter()
        curve = dome_curve(
            outer_radius=OUTER_RADIUS, thickness=THICKNESS, material=RESIN, max_force=MAX_FORCE, n_points=12
        )
        seconds["axisymmetric"] = time.perf_counter() - start
        levels["axisymmetric"] = float(curve.travel[-1]) / MAX_FORCE
        progress("dome: axisymmetric, rim free to slide")
        start = time.perf_counter()
        sliding = float(
            dome_compliance(
                outer_radius=OUTER_RADIUS, thickness=THICKNESS, material=RESIN, max_force=MAX_FORCE, base="sliding"
            )
        )
        seconds["sliding"] = time.perf_counter() - start
        report.result(
            "dome_curve_axisymmetric",
            {
                "travel": np.asarray(curve.travel),
                "force": np.asarray(curve.force),
                "contact_radius": np.asarray(curve.contact_radius),
            },
        )
        report.result("compliance_axisymmetric_sliding", sliding)
    for level, value in levels.items():
        report.result(f"compliance_{level}", value)
        report.result(f"travel_at_5N_{level}", value * MAX_FORCE)
    report.result("dome_seconds", seconds)
    return dict(levels=levels, curve=curve, sliding=sliding, seconds=seconds)


def design(report, quick):
    """Part 3: the default design at Reissner, then confirmed at the axisymmetric level from
    that answer (what ``magdesign solve --fidelity auto`` does)."""
    spec = default_spec()
    problem, _ = problem_from_spec(spec)
    progress(f"design at {fidelity_levels(spec)} (first call compiles)")
    first = solve(problem)
    warm = solve(problem)
    answers = [(fidelity_levels(spec), first)]
    exact = exact_levels(spec)
    if not quick and exact is not None:
        exact_problem, _ = problem_from_spec(exact)
        progress(f"design confirmed at {fidelity_levels(exact)} (compiles for minutes)")
        start = {
            v.name: min(max(first.parameters[v.name], float(v.lower)), float(v.upper)) for v in exact_problem.variables
        }
        answers.append((fidelity_levels(exact), solve(exact_problem, start=start)))
    rows = {}
    for levels, answer in answers:
        rows[levels] = {
            "status": answer.status,
            "gap": answer.parameters["geometry.gap"],
            "thickness": answer.parameters["mechanics.thickness"],
            "steps": answer.steps,
            "seconds": answer.seconds,
            **{k: float(v) for k, v in answer.outputs.items()},
        }
    report.result("design", rows)
    report.result("design_reissner_warm_seconds", warm.seconds)
    return dict(rows=rows, warm=warm.seconds)


def sensor_scene():
    """The paper's sensor (8 mm / 2 mm dome, rest gap 6.4 mm + 1.6 mm) with Eq. 2's lag and
    the AK8963's saturation, noise and quantisation; the exact field, so that the inverse can
    fit the magnet's x and y too. Reissner dome: linear, so its travel is the force times C."""
    spec = copy.deepcopy(default_spec())
    del spec["design"]
    spec["scene"]["effects"] = ["viscoelastic_lag", "saturation", "noise", "quantisation"]
    spec["scene"]["lag_time_constant"] = float(time_constant_from_pole(POLE, SAMPLE_RATE))
    spec["magnet"]["fidelity"] = "exact"
    spec["mechanics"]["thickness"] = THICKNESS
    spec["geometry"]["gap"] = PAPER_MARGIN + TRAVEL
    return scene_from_spec(spec)


def effect(scene, name):
    return next(e for e in scene.effects if e.name == name)


def ramps(report, quick):
    """Part 4: each ramp of Table I simulated at 100 Hz through the scene's lag; the force a
    static reading implies, against the applied force."""
    scene = sensor_scene()
    tau = float(effect(scene, "viscoelastic_lag").time_constant)
    compliance = float(
        dome_compliance(
            outer_radius=OUTER_RADIUS, thickness=THICKNESS, material=RESIN, max_force=MAX_FORCE, fidelity="reissner"
        )
    )
    rates = sorted(set(TRAIN_RAMPS) | set(TEST_RAMPS.values()))
    # One time grid for every ramp (one compiled program): the slowest ramp, then a hold.
    time_grid = np.arange(int(round((MAX_FORCE / min(rates) + HOLD) * SAMPLE_RATE)) + 1) / SAMPLE_RATE
    series = {}
    for index, rate in enumerate(rates):
        progress(f"ramp {rate} N/s: simulating {time_grid.size} samples at {SAMPLE_RATE:g} Hz")
        force = np.minimum(rate * time_grid, MAX_FORCE)
        result = simulate(scene, Loads(force, time=time_grid), key=jax.random.key(index))
        end = int(round(MAX_FORCE / rate * SAMPLE_RATE))  # the sample where the ramp reaches 5 N
        travel = -np.asarray(result.displacement[:, 2])
        series[rate] = {
            "force": force[: end + 1],
            "read": travel[: end + 1] / compliance,  # the force the lagged travel stands for
            "readings": np.asarray(result.readings[: end + 1]),
            "reading_lag": float(result.chip_field[-1, 0, 2] - result.chip_field[end, 0, 2]),
        }
    table = []
    for rate in rates:
        s = series[rate]
        error = s["read"] - s["force"]
        table.append(
            {
                "rate": rate,
                "max_error": float(np.max(np.abs(error))),
                "error_at_5N": float(error[-1]),
                "reading_lag": s["reading_lag"],
                "expected": -rate * tau,
            }
        )
    delay = float(lag_pole(tau, SAMPLE_RATE))
    delay = delay / ((1 - delay) * SAMPLE_RATE)
    report.result("lag_time_constant", tau)
    report.result("lag_ramp_delay", delay)
    report.result("lag_by_ramp", table)
    return dict(scene=scene, tau=tau, delay=delay, compliance=compliance, series=series, table=table, quick=quick)


def deviations(estimate, force):
    """MAE, max abs error, share within 10 %, relative deviation covering 95 % and 100 % of points."""
    error = estimate - force
    loaded = force > 0
    relative = np.abs(error[loaded]) / force[loaded]
    return {
        "mae": float(np.mean(np.abs(error))),
        "max": float(np.max(np.abs(error))),
        "within_10": float(np.mean(relative <= 0.10)),
        "deviation_95": float(np.quantile(relative, 0.95)),
        "deviation_all": float(np.max(relative)),
    }


def inverse(report, lag):
    """Part 5: invert the simulated readings to the magnet's displacement (magdesign.inverse,
    static model), then to force through the dome; also with the lag undone (Eq. 2 inverted)."""
    scene, compliance, tau = lag["scene"], lag["compliance"], lag["tau"]
    noise = float(effect(scene, "noise").sigma[2])  # the chip's z axis
    lsb = float(effect(scene, "quantisation").lsb[2])
    sigma = np.hypot(noise, lsb / np.sqrt(12))  # rounding adds lsb^2 / 12 to the variance
    names = dict(TEST_RAMPS) if lag["quick"] else {**TEST_RAMPS, **{f"train {r}": r for r in TRAIN_RAMPS}}
    readings = np.concatenate([lag["series"][rate]["readings"] for rate in names.values()])
    candidates = displacement_grid([0.0], [0.0], np.linspace(0.2 * mm, -2.4 * mm, 14))
    progress(f"inverting {readings.shape[0]} readings (compiles for tens of seconds)")
    start = time.perf_counter()
    inversion = invert_displacement(scene, readings, noise=sigma, resolution=1e-6, candidates=candidates, starts=2)
    travel = -np.asarray(inversion.displacement[:, 2])
    seconds = time.perf_counter() - start
    ok = np.asarray(inversion.status == InverseStatus.successful)
    a = float(lag_pole(tau, SAMPLE_RATE))
    estimates, offset = {}, 0
    for name, rate in names.items():
        s = lag["series"][rate]
        n = s["force"].size
        static = travel[offset : offset + n] / compliance
        # undo y[n] = a y[n-1] + (1 - a) x[n], from rest
        compensated = (static - a * np.concatenate([[0.0], static[:-1]])) / (1 - a)
        estimates[name] = {"force": s["force"], "static": static, "compensated": compensated}
        offset += n
    stats = {}
    for kind in ("static", "compensated"):
        stats[kind] = {name: deviations(e[kind], e["force"]) for name, e in estimates.items()}
        test = [estimates[name] for name in TEST_RAMPS]
        stats[kind]["test"] = deviations(
            np.concatenate([e[kind] for e in test]), np.concatenate([e["force"] for e in test])
        )
        train = [e for name, e in estimates.items() if name.startswith("train")]
        if train:
            stats[kind]["train"] = deviations(
                np.concatenate([e[kind] for e in train]), np.concatenate([e["force"] for e in train])
            )
    report.result("inverse", stats)
    report.result("inverse_noise", sigma)
    report.result("inverse_successful_share", float(ok.mean()))
    report.result("inverse_seconds", seconds)
    return dict(
        estimates=estimates,
        stats=stats,
        sigma=sigma,
        noise=noise,
        lsb=lsb,
        ok=float(ok.mean()),
        pole=a,
        seconds=seconds,
        count=readings.shape[0],
    )


def contact_stiffening(dome):
    """The axisymmetric path's secant compliance as a multiple of Reissner's at its first and
    last travel, and its contact radius at 5 N, in words ("" without the path: --quick)."""
    curve = dome["curve"]
    if curve is None:
        return ""
    travel, force = np.asarray(curve.travel), np.asarray(curve.force)
    ratio = travel / force / dome["levels"]["reissner"]
    return (
        f"the axisymmetric model's secant compliance is {ratio[0]:.2f} times Reissner's at a travel of "
        f"{travel[0] / mm:.2f} mm and {ratio[-1]:.2f} times at 5 N, {travel[-1] / mm:.2f} mm, as the contact "
        f"grows to a radius of {float(curve.contact_radius[-1]) / mm:.2f} mm"
    )


def comparison(report, sat, dome, des, inv, quick):
    levels = dome["levels"]
    rows = [
        {
            "quantity": "saturation distance, Eq. 1",
            "published": "6 mm",
            "source": "Sec. II.A",
            "magdesign": mm_text(sat["closed"]),
            "difference": mm_text(sat["closed"] - PAPER_SATURATION_DISTANCE, 3),
            "why": f"within {SATURATION_TOLERANCE / mm:g} mm: the paper rounds the root of Eq. 1 to whole mm",
        },
        {
            "quantity": "saturation distance, measured",
            "published": "just below 6 mm",
            "source": "Sec. II.A, Fig. 3",
            "magdesign": f"{mm_text(sat['exact'])} (exact field)",
            "difference": f"{mm_text(sat['exact'] - PAPER_SATURATION_DISTANCE, 3)} from 6 mm",
            "why": f"{'agrees' if sat['exact'] < PAPER_SATURATION_DISTANCE else 'disagrees'}: Fig. 3's measured "
            "point is not tabulated, so 'just below 6 mm' is compared as a side of 6 mm only; the model "
            f"saturates {100 * abs(1 - sat['exact'] / PAPER_SATURATION_DISTANCE):.1f} % "
            f"{'below' if sat['exact'] < PAPER_SATURATION_DISTANCE else 'above'} it (on the axis the exact "
            "cylinder field is Eq. 1)",
        },
    ]
    slenderness = THICKNESS / (OUTER_RADIUS - THICKNESS / 2)
    stiffening = contact_stiffening(dome)
    for level, label, why in (
        (
            "reissner",
            "Reissner, mid-surface",
            "linear point-load formula: at 5 N the travel is "
            f"{TRAVEL / THICKNESS:.1f} t and the plate's contact spreads over the apex, which stiffens the dome beyond "
            f"Reissner's value{f' ({stiffening})' if stiffening else ''}; the thick wall (t/R = {slenderness:.2f}) acts "
            "the other way (its transverse shear and compression under the plate make it softer than Reissner, the "
            f"more so at light loads); outside the {100 * DOME_TOLERANCE:g} % tolerance, as expected",
        ),
        (
            "reissner_outer",
            "Reissner, outer radius",
            f"the same formula with R = {OUTER_RADIUS / mm:g} mm: softer still",
        ),
        (
            "axisymmetric",
            "axisymmetric FE",
            f"within {100 * DOME_TOLERANCE:g} %: frictionless plate (the paper's Abaqus "
            "model: friction 0.8), axisymmetric (not 3-D tets), 'about 0.32 mm/N' read off Fig. 6",
        ),
    ):
        if level in levels:
            value = levels[level] * MAX_FORCE
            rows.append(
                {
                    "quantity": f"travel at 5 N, {label}",
                    "published": "1.6 mm (0.32 mm/N)",
                    "source": "Sec. II.B, Fig. 6",
                    "magdesign": mm_text(value),
                    "difference": percent(value / TRAVEL - 1),
                    "why": why,
                }
            )
        else:
            rows.append(
                {
                    "quantity": f"travel at 5 N, {label}",
                    "published": "1.6 mm (0.32 mm/N)",
                    "source": "Sec. II.B, Fig. 6",
                    "magdesign": "not run (--quick)",
                    "difference": "-",
                    "why": "the axisymmetric dome compiles on its first call (tens of seconds)",
                }
            )
    for levels_name, row in des["rows"].items():
        rows.append(
            {
                "quantity": f"wall thickness for 0.32 mm/N ({levels_name})",
                "published": "2 mm",
                "source": "Sec. II.B",
                "magdesign": mm_text(row["thickness"]),
                "difference": percent(row["thickness"] / THICKNESS - 1),
                "why": "the dome level's travel at t = 2 mm is above 1.6 mm (rows above): a thicker wall "
                "meets 0.32 mm/N",
            }
        )
    if quick:
        rows.append(
            {
                "quantity": "wall thickness for 0.32 mm/N (dome axisymmetric)",
                "published": "2 mm",
                "source": "Sec. II.B",
                "magdesign": "not run (--quick)",
                "difference": "-",
                "why": "the axisymmetric confirmation compiles for minutes",
            }
        )
    row = des["rows"][next(iter(des["rows"]))]
    rows += [
        {
            "quantity": "closest approach at 5 N",
            "published": "6.4 mm",
            "source": "Sec. II.A, Fig. 3",
            "magdesign": mm_text(row["closest_gap"]),
            "difference": mm_text(row["closest_gap"] - PAPER_MARGIN, 3),
            "why": "modelling choice: the default spec limits the field to 4.8 mT itself, without the paper's margin",
        },
        {
            "quantity": "rest gap",
            "published": "8.0 mm (6.4 + 1.6, derived)",
            "source": "Sec. II.A + II.B",
            "magdesign": mm_text(row["gap"]),
            "difference": mm_text(row["gap"] - PAPER_MARGIN - TRAVEL, 3),
            "why": "the margin of the row above; the travel at 5 N is the 1.6 mm target at every level",
        },
    ]
    test = {kind: inv["stats"][kind]["test"] for kind in ("static", "compensated")}
    moderate = {kind: inv["stats"][kind]["moderate"] for kind in ("static", "compensated")}
    steep = {kind: inv["stats"][kind]["steep"] for kind in ("static", "compensated")}
    model = (
        "simulated readings of the model itself (lag, 1-LSB noise, quantisation): the MLP's error on the "
        "real sensor also holds what is not modelled"
    )
    rows += [
        {
            "quantity": "force MAE, test ramps",
            "published": f"{MLP_MAE_TEST} N (MLP)",
            "source": "Sec. IV",
            "magdesign": f"{number(test['static']['mae'], 3)} N static inverse, {number(test['compensated']['mae'], 3)} N "
            "lag undone",
            "difference": f"{percent(test['static']['mae'] / MLP_MAE_TEST - 1)} (static)",
            "why": model,
        },
        {
            "quantity": "max abs error, steep 0.5 N/s",
            "published": f"{MLP_MAX_STEEP} N",
            "source": "Sec. V",
            "magdesign": f"{number(steep['static']['max'], 3)} N static, {number(steep['compensated']['max'], 3)} N lag undone",
            "difference": f"{percent(steep['static']['max'] / MLP_MAX_STEEP - 1)} (static)",
            "why": f"the lag alone: the static inverse reads the force {inv['delay']:.3f} s late (Eq. 2 at 100 Hz), "
            "0.5 N/s x that",
        },
        {
            "quantity": "max abs error, moderate 0.05 N/s",
            "published": f"{MLP_MAX_MODERATE} N",
            "source": "Sec. V",
            "magdesign": f"{number(moderate['static']['max'], 3)} N static",
            "difference": percent(moderate["static"]["max"] / MLP_MAX_MODERATE - 1),
            "why": "slow ramp: the lag is 0.05 N/s x tau; the MLP's error here is not the lag but what the model "
            "leaves out",
        },
        {
            "quantity": "moderate ramp: share within 10 %",
            "published": "> 95 %",
            "source": "Sec. V, Fig. 12",
            "magdesign": f"{moderate['static']['within_10']:.1%} static",
            "difference": f"{100 * (moderate['static']['within_10'] - MODERATE_SHARE_WITHIN_10):+.1f} points",
            "why": "agrees, at the paper's figure: the lag's relative error exceeds 10 % below 10 r tau = "
            f"{10 * TEST_RAMPS['moderate'] * inv['tau']:.2f} N, i.e. on "
            f"{10 * TEST_RAMPS['moderate'] * inv['tau'] / MAX_FORCE:.1%} of a ramp to 5 N",
        },
        {
            "quantity": "steep ramp: deviation covering 95 %",
            "published": "> 25 %",
            "source": "Sec. V, Fig. 12",
            "magdesign": f"{steep['static']['deviation_95']:.0%} static, {steep['compensated']['deviation_95']:.0%} lag undone",
            "difference": f"{100 * (steep['static']['deviation_95'] - STEEP_DEVIATION_95):+.0f} points (static)",
            "why": "agrees (> 25 %); the static inverse ignores the lag, which an MLP trained on every slope can "
            "partly learn (the paper's steep ramp over-predicts at high forces, Sec. V)",
        },
        {
            "quantity": "steep ramp: deviation covering all points",
            "published": "38 %",
            "source": "Sec. V, Fig. 12",
            "magdesign": f"{steep['static']['deviation_all']:.0%} static",
            "difference": f"{100 * (steep['static']['deviation_all'] - STEEP_DEVIATION_ALL):+.0f} points",
            "why": "a lag reads about nothing at the ramp's first samples (relative error near 100 %)",
        },
    ]
    if "train" in inv["stats"]["static"]:
        train = inv["stats"]["static"]["train"]["mae"]
        rows.append(
            {
                "quantity": "force MAE, train ramps",
                "published": f"{MLP_MAE_TRAIN} N (MLP)",
                "source": "Sec. IV",
                "magdesign": f"{number(train, 3)} N static inverse",
                "difference": percent(train / MLP_MAE_TRAIN - 1),
                "why": model,
            }
        )
    report.comparison(rows)


def figures_field(report, sat):
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for (label, values), style, color in zip(sat["curves"].items(), ("-", ":", "--"), ("0.5", "k", "C2")):
        ax.semilogy(sat["z"] / mm, values / mT, style, color=color, lw=2 if style == "-" else 1, label=label)
    ax.axhline(SATURATION / mT, color="k", lw=0.8)
    ax.axvline(sat["closed"] / mm, color="C0", lw=0.8, label=f"magdesign: {sat['closed'] / mm:.3f} mm")
    ax.axvline(PAPER_SATURATION_DISTANCE / mm, color="C3", lw=0.8, ls="--", label="paper, Eq. 1: 6 mm")
    ax.axvline(PAPER_MARGIN / mm, color="C3", lw=0.8, ls=":", label="paper's margin: 6.4 mm")
    ax.set_xlabel("distance above the magnet's top face z (mm)")
    ax.set_ylabel("B_z on the axis (mT)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    report.figure(fig, "field.png", "On-axis field of the N35 magnet (3 x 1 mm, Br 1.17 T) and the AK8963's 4.8 mT")


def figure_dome(report, dome):
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    force = np.linspace(0.0, 6.0, 50)
    ax.plot(dome["levels"]["reissner"] * force / mm, force, label="Reissner, mid-surface radius 7 mm")
    ax.plot(dome["levels"]["reissner_outer"] * force / mm, force, ":", label="Reissner, radius 8 mm")
    if dome["curve"] is not None:
        curve = dome["curve"]
        ax.plot(
            np.r_[0.0, curve.travel] / mm, np.r_[0.0, curve.force], "o-", ms=3, label="axisymmetric FE (bonded rim)"
        )
    ax.plot([0.0, TRAVEL / mm], [0.0, MAX_FORCE], "k--", lw=0.8, label="0.32 mm/N secant")
    ax.plot(TRAVEL / mm, MAX_FORCE, "k*", ms=12, label="paper: 1.6 mm at 5 N (FEM, experiment)")
    ax.set_xlabel("plate travel (mm)")
    ax.set_ylabel("force (N)")
    ax.set_xlim(0, None)
    ax.set_ylim(0, 6)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    report.figure(fig, "dome.png", "Force-travel of the 8 mm / 2 mm resin dome pressed by a flat plate, at each level")


def figure_lag(report, lag):
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    rates = sorted(lag["series"])
    for rate, color in zip(rates, plt.cm.viridis(np.linspace(0.0, 0.9, len(rates)))):
        s = lag["series"][rate]
        ax.plot(s["force"], s["read"] - s["force"], color=color, label=f"{rate:g} N/s")
    ax.set_xlabel("applied force (N)")
    ax.set_ylabel("force read (lagged travel / C) - applied (N)")
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    ax.grid(alpha=0.3)
    report.figure(fig, "lag.png", "Force error of a static reading through Eq. 2's lag, for the ramps of Table I")


def figure_inverse(report, inv):
    fig, (left, right) = plt.subplots(1, 2, figsize=(10.0, 4.0))
    for name, color in zip(TEST_RAMPS, ("C0", "C3")):
        e = inv["estimates"][name]
        left.plot(e["force"], e["static"], color=color, lw=1, label=f"{name} {TEST_RAMPS[name]} N/s, static")
        left.plot(e["force"], e["compensated"], color=color, lw=0.3, alpha=0.5, label=f"{name}, lag undone")
        for kind, style in (("static", "-"), ("compensated", ":")):
            relative = np.sort(np.abs(e[kind] - e["force"])[e["force"] > 0] / e["force"][e["force"] > 0])
            right.plot(100 * relative, np.linspace(0, 1, relative.size), style, color=color, label=f"{name}, {kind}")
    left.plot([0, 5], [0, 5], "k", lw=0.5)
    left.plot([0, 5], [0, 5.5], "k:", lw=0.5)
    left.plot([0, 5], [0, 4.5], "k:", lw=0.5)
    left.set_xlabel("applied force (N)")
    left.set_ylabel("estimated force (N)")
    left.legend(fontsize=7)
    right.plot(10, MODERATE_SHARE_WITHIN_10, "C0*", ms=10, label="paper: moderate, 95 % within 10 %")
    right.plot(100 * STEEP_DEVIATION_ALL, 1.0, "C3*", ms=10, label="paper: steep, all within 38 %")
    right.set_xscale("log")
    right.set_xlim(0.1, 100)
    right.set_xlabel("relative deviation (%)")
    right.set_ylabel("cumulative fraction of points")
    right.legend(fontsize=7)
    for ax in (left, right):
        ax.grid(alpha=0.3, which="both")
    report.figure(
        fig, "inverse.png", "Model-based force inverse on the simulated test ramps (cf. the paper's Figs. 11, 12)"
    )


def main(argv=None):
    args = arguments(NAME, argv, description=__doc__.splitlines()[0])
    quick = args.quick
    report = Report(NAME, f"Dome-Hall sensor: soft dome, N35 magnet and AK8963 Hall chip ({PAPER})", args.out, quick)
    sat = saturation_distance(report)
    dome = dome_levels(report, quick)
    des = design(report, quick)
    lag = ramps(report, quick)
    inv = inverse(report, lag)
    inv["tau"], inv["delay"] = lag["tau"], lag["delay"]
    comparison(report, sat, dome, des, inv, quick)
    write_sections(report, sat, dome, des, lag, inv, quick)
    progress("writing the report")
    report.write()


def gap_text(rows):
    (cheap, first), (exact, confirmed) = rows.items()
    return (
        f"From {cheap} to {exact} the gap moves by {number((confirmed['gap'] - first['gap']) / 1e-6, 2)} um (the "
        "field limit fixes the closest approach, and the travel at 5 N is the 1.6 mm target at both) and the "
        f"wall by {(confirmed['thickness'] - first['thickness']) / 1e-6:+.1f} um; the confirmation costs "
        f"{confirmed['seconds'] / first['seconds']:.0f} times the first solve, first calls both."
    )


def write_sections(report, sat, dome, des, lag, inv, quick):
    report.text(
        "Published numbers are from the paper's sections, equations, figures and tables named in the source "
        "column; every magdesign number is computed by this run. The paper's curves (Figs. 3, 6, 11-13) are "
        "not tabulated, so only the numbers its text states are compared."
    )

    report.heading("1. Saturation distance")
    report.text(
        "Where the on-axis field of the N35 magnet falls to the AK8963's 4.8 mT, found by bisection on "
        "`fields.cylinder_axial` (Eq. 1) and on `fields.cylinder` (exact, elliptic integrals) at the axis; "
        "the dipole level for scale."
    )
    report.table(
        ["model", "saturation distance (mm)", "B_z at 6 mm (mT)", "B_z at 6.4 mm (mT)"],
        [
            ["Eq. 1, closed form", sat["closed"] / mm, sat["at_six"] / mT, sat["at_margin"] / mT],
            [
                "exact cylinder field",
                sat["exact"] / mm,
                *np.asarray(on_axis([PAPER_SATURATION_DISTANCE, PAPER_MARGIN])) / mT,
            ],
            [
                "dipole",
                sat["dipole"] / mm,
                *np.asarray(on_axis([PAPER_SATURATION_DISTANCE, PAPER_MARGIN], "dipole")) / mT,
            ],
        ],
    )
    report.text(
        f"The paper's 6.4 mm margin keeps the field at {sat['at_margin'] / SATURATION:.0%} of the saturation. "
        "Fig. 3's measured curve saturates 'just below 6 mm', as the model does; its data are not tabulated."
    )
    figures_field(report, sat)

    report.heading("2. The dome's force-travel curve")
    levels = dome["levels"]
    rows = [
        [
            "Reissner, R = R_o - t/2 (magdesign's level)",
            levels["reissner"] / mm,
            levels["reissner"] * MAX_FORCE / mm,
            "-",
        ],
        ["Reissner, R = R_o", levels["reissner_outer"] / mm, levels["reissner_outer"] * MAX_FORCE / mm, "-"],
    ]
    if dome["curve"] is not None:
        rows.append(
            [
                "axisymmetric FE, bonded rim (2 x 16 mesh)",
                levels["axisymmetric"] / mm,
                levels["axisymmetric"] * MAX_FORCE / mm,
                dome["seconds"]["axisymmetric"],
            ]
        )
        rows.append(
            [
                "axisymmetric FE, rim free to slide",
                dome["sliding"] / mm,
                dome["sliding"] * MAX_FORCE / mm,
                dome["seconds"]["sliding"],
            ]
        )
    report.table(["level", "secant compliance at 5 N (mm/N)", "travel at 5 N (mm)", "first call (s)"], rows)
    slenderness = THICKNESS / (OUTER_RADIUS - THICKNESS / 2)
    text = (
        f"Reissner's point-load formula is linear and thin-shell. The paper's wall is thick (t/R = "
        f"{slenderness:.2f} at the mid-surface): its transverse shear and its compression under the plate make "
        f"the dome softer than Reissner, the more so at light loads. At 5 N, though, the travel is "
        f"{TRAVEL / THICKNESS:.1f} of the wall and the plate's contact spreads over the apex, which stiffens "
        "the dome beyond Reissner's value, so the formula overestimates the travel at 5 N. "
    )
    if dome["curve"] is not None:
        text += (
            f"The axisymmetric finite-strain model (frictionless plate, `mechanics.dome_curve`) shows both: "
            f"{contact_stiffening(dome)}. The rim's support alone moves the travel by "
            f"{dome['sliding'] / levels['axisymmetric'] - 1:.0%} (bonded "
            "against sliding), so the remaining difference from the paper's Abaqus model (3-D tetrahedra, "
            "plate friction 0.8, a base not stated) is within what such modelling choices move."
        )
    else:
        text += "The axisymmetric level is skipped in --quick mode."
    report.text(text)
    figure_dome(report, dome)

    report.heading("3. The design: Reissner, then confirmed at the axisymmetric level")
    report.text(
        "The built-in default design (`magdesign/design/default.toml`): rest gap and wall thickness free, "
        "0.32 mm/N at 5 N as the target, the largest field component at most 4.8 mT, the largest sensitivity. "
        "Solved at the spec's levels, then from that answer at the exact levels (`spec.design.exact_levels`), "
        "as `magdesign solve --fidelity auto` does. Times are wall times of this run, compiling included; the "
        "machine is shared, so they are inflated."
    )
    report.table(
        [
            "levels",
            "status",
            "rest gap (mm)",
            "wall (mm)",
            "closest approach (mm)",
            "compliance (mm/N)",
            "sensitivity (mT/N)",
            "steps",
            "time (s)",
        ],
        [
            [
                name,
                r["status"],
                r["gap"] / mm,
                r["thickness"] / mm,
                r["closest_gap"] / mm,
                r["compliance"] / mm,
                r["sensitivity"] / mT,
                r["steps"],
                r["seconds"],
            ]
            for name, r in des["rows"].items()
        ],
    )
    report.text(
        f"A second, warm solve at the Reissner level took {number(des['warm'] * 1e3, 3)} ms. "
        + ("The axisymmetric confirmation is skipped in --quick mode." if quick else gap_text(des["rows"]))
    )

    report.heading("4. Viscoelastic lag at the paper's ramp rates")
    report.text(
        f"Eq. 2's pole {POLE} at {SAMPLE_RATE:g} Hz is a first-order lag of time constant "
        f"tau = {lag['tau']:.4f} s (`mechanics.time_constant_from_pole`). The scene's `viscoelastic_lag` effect "
        "delays the magnet's travel by it. Each ramp of Table I (0.025 to 0.8 N/s to 5 N; the text says 0.7 N/s "
        "but the table lists 0.8) is simulated at 100 Hz on the paper's sensor: the 8 / 2 mm dome (Reissner, "
        f"linear: C = {lag['compliance'] / mm:.4f} mm/N), the rest gap 6.4 + 1.6 mm, the exact field, the AK8963's "
        "saturation, noise and quantisation. The force a static reading stands for is the lagged travel / C. "
        f"On a ramp of rate r it settles to r a / ((1 - a) fs) = r x {lag['delay']:.4f} s behind the applied force "
        "(the 100 Hz filter's delay, just under tau). The paper identifies Eq. 2 from the calibrated sensor's "
        "step response (Fig. 13), which also holds the rig's own force build-up (Sec. V), so taking all of it "
        "as the resin's lag bounds the resin's effect from above."
    )
    report.table(
        [
            "ramp (N/s)",
            "largest force error (N)",
            "error when 5 N is reached (N)",
            "-r tau (N)",
            "B_z short of its settled value at 5 N (uT)",
        ],
        [[r["rate"], r["max_error"], r["error_at_5N"], r["expected"], r["reading_lag"] / uT] for r in lag["table"]],
    )
    figure_lag(report, lag)

    report.heading("5. Model-based force inverse against the paper's MLP")
    report.text(
        f"`inverse.invert_displacement` fits the magnet's displacement (x, y, z) to each 100 Hz reading "
        f"({inv['count']} readings) with the static forward model (no lag, no noise, no rounding), noise "
        f"sigma = {inv['sigma'] / uT:.3f} uT per axis (the scene's {inv['noise'] / uT:.2f} uT noise, magdesign's "
        f"default of one LSB for the AK8963 as the paper gives none, and the {inv['lsb'] / uT:.2f} uT LSB's "
        f"rounding); {inv['ok']:.1%} of the inversions report `successful` "
        f"({number(inv['seconds'], 3)} s, compiling included). Force = travel / C. 'Lag undone' inverts Eq. 2 "
        "sample by sample, x[n] = (y[n] - a y[n-1]) / (1 - a), which multiplies white noise by "
        f"sqrt(1 + a^2) / (1 - a) = {np.hypot(1, inv['pole']) / (1 - inv['pole']):.0f}."
    )
    rows = []
    for kind in ("static", "compensated"):
        for name, s in inv["stats"][kind].items():
            rows.append(
                [
                    kind if kind == "static" else "lag undone",
                    name,
                    s["mae"],
                    s["max"],
                    f"{s['within_10']:.1%}",
                    f"{s['deviation_95']:.1%}",
                    f"{s['deviation_all']:.0%}",
                ]
            )
    report.table(
        [
            "inverse",
            "ramps",
            "MAE (N)",
            "max abs error (N)",
            "share within 10 %",
            "deviation covering 95 %",
            "largest deviation",
        ],
        rows,
    )
    steep = {kind: inv["stats"][kind]["steep"]["mae"] for kind in ("static", "compensated")}
    report.text(
        f"The paper's MLP (3-10-5-1, trained on nine ramps) reaches an MAE of {MLP_MAE_TEST} N on its two test "
        "ramps. The model-based inverse here sees only what the model holds (the lag, the AK8963's noise and "
        "rounding), so its error is a floor, not a prediction for the real sensor. On the steep ramp the lag is "
        f"the error (0.5 N/s x tau); undoing it takes that ramp's MAE from {number(steep['static'], 3)} N to "
        f"{number(steep['compensated'], 3)} N, the amplified noise. On the moderate ramp the lag is "
        f"{TEST_RAMPS['steep'] / TEST_RAMPS['moderate']:g} times smaller, and the MLP's {MLP_MAX_MODERATE} N "
        "largest error there comes from what the model leaves out (hysteresis, the rig's dynamics, nonlinear "
        "viscoelasticity, the fit itself)."
    )
    figure_inverse(report, inv)


if __name__ == "__main__":
    main()
