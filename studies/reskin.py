"""ReSkin: a magnetised elastomer skin over five MLX90393 chips, at magdesign's skin scene.

R. Bhirangi, T. Hellebrekers, C. Majidi and A. Gupta, "ReSkin: versatile, replaceable,
lasting tactile skins" (2021) (docs/references.md), "the paper" below: a 2-3 mm elastomer
skin loaded with magnetised microparticles over a board of five MLX90393 chips, read by a
learned model, which detects 0.1 N and localises a contact to about 1 mm. The board is the
paper's open "5X ReSkin" design (the reskin_sensor repository's circuits/5X_ReSkin.Zip):
its pick-and-place file places the five chips in a cross at 7 mm pitch on a 20 mm square.

The study builds that skin (magdesign.scene.skin_scene.SkinScene) and

1. sets the model's bounds beside the paper's figures: the Cramer-Rao bound of the normal
   and shear forces and of the contact's position over the chips' area, the saturation of
   the chips and the Earth's field as an error in force, at the paper's 0.1 N;
2. sweeps the chips' pitch and the skin's thickness (one compiled scene structure: the
   pitch moves the chips, the thickness is a parameter), with the first-order spread of each
   output under the tolerances of the magnetisation and the chips' placement
   (magdesign.design.tolerance.first_order), and a Monte Carlo of those tolerances at
   ReSkin's design (magdesign.design.tolerance.monte_carlo);
3. solves the polarisation that halves ReSkin's normal-force bound with the same chips and
   no chip saturating under a 5 N press (magdesign.design.solve), and checks the answer with
   the sweep's scene;
4. evaluates an eFlesh-like skin (V. Pattabiraman, Z. Huang, D. Panozzo, D. Zorin, L. Pinto
   and R. Bhirangi, "eFlesh: highly customizable magnetic touch sensing using cut-cell
   microstructures" (2025)): examples/eflesh.toml's discrete magnets in a soft lattice taken
   as an effective layer, over the same board's chips, beside eFlesh's published figures.

What neither the paper's summary figures nor the board give (the elastomer's modulus, the
magnetisation, the chips' noise, the indenter) is an assumption named in the report.

    python studies/reskin.py [--quick] [--plot] [--out DIR]
"""

import dataclasses
import math
import pathlib

import equinox as eqx
import numpy as np
from _report import Report, arguments, progress

from magdesign.design import solve
from magdesign.design.tolerance import first_order, monte_carlo
from magdesign.mechanics.skin_layer import SpectralGrid
from magdesign.scene import loads_from_spec, outputs, scene_from_spec, with_parameters
from magdesign.scene.skin_scene import SATURATION_FORCE_CAP, linear_grid
from magdesign.spec.design import load_spec, problem_from_spec
from magdesign.spec.tolerance import tolerance_problem_from_spec
from magdesign.units import mm, mT

NAME = "reskin"
MIL = 25.4e-6  # m: the board files' unit, a thousandth of an inch
mN = 1e-3  # N

# The 5X ReSkin board (reskin_sensor repository, circuits/5X_ReSkin.Zip). "Pick Place for
# PCB.txt": five "Melexis MLX90393ELW-ABA-011-SP", centres (Mid X, Mid Y) in mil, U1, U3,
# U5, U2, U4. PCB.Outline: the sensing square spans x 2165.35-2952.76 mil (20.0 mm) and
# y 2755.90-3549.24 mil, centred on U1 (x exactly, y within 1 mil); circuits/README.md:
# "20x29mm" with the connector's tab.
BOARD_CHIPS_MIL = (
    (2559.055, 3153.543),
    (2834.646, 3153.543),
    (2283.465, 3155.543),
    (2559.055, 3429.134),
    (2559.055, 2877.953),
)
BOARD_SIDE = (2952.76 - 2165.35) * MIL  # m, the square's side along x (PCB.Outline)

# Published: the paper's summary figures, as stated with its release (the body's sections
# were not at hand, so the report cites the summary, not a section or figure).
DETECTED_FORCE = 0.1  # N: "detects 0.1 N"
LOCALISATION = 1.0 * mm  # "localises contact to about 1 mm" (a learned model's test-set error)
THICKNESS_RANGE = (2.0 * mm, 3.0 * mm)  # "2-3 mm" skins
CHIPS = 5  # five MLX90393 magnetometers (also the board's pick-and-place file)

# Assumptions (stated in the report; no source at hand gives them).
THICKNESS = 2.0 * mm  # the thinner end of the published 2-3 mm
SHEAR_MODULUS = 100e3  # Pa: a soft silicone of about 0.3 MPa Young's modulus
POISSON = 0.49  # nearly incompressible
POLARIZATION = 20 * mT  # J0 of the particle-loaded elastomer, through the thickness
DEPTH = 1.0 * mm  # the chips' Hall plates below the skin's bonded face
SPHERE = 2.0 * mm  # the indenter's radius
SKIN_SIDE = 20 * mm  # the skin covers the board's sensing square
EARTH = ("0 T", "0 T", "50 uT")  # the background the chips read, as examples/skin.toml
# The chips' noise: one LSB per axis of the MLX90393 at GAIN_SEL = 7, RES_XYZ = 0 (the
# skin scene's default; magdesign.transducers.mlx90393), the setting that the board's
# firmware library (arduino-MLX90393's begin()) chooses. The datasheet's RMS noise at the
# firmware's OSR = 3, DIG_FILT = 7 is not in the copies at hand: the noise is assumed.
NOISE_NOTE = "one LSB per axis (0.150 uT x, y; 0.242 uT z)"
# Tolerances of the Monte Carlo and of the sweep's spreads (assumed): the magnetisation
# varies with the particle loading from skin to skin; the chips are placed by a pick-and-place.
POLARIZATION_TOLERANCE = "10 %"
PLACEMENT_TOLERANCE = "50 um"
# The design's bounds on J0: up to 10 times ReSkin's assumed 20 mT.
DESIGN_BOUNDS = ("5 mT", "200 mT")
DETECTION_SIGMAS = 3.0  # a force is "detected" at three standard deviations of its estimate
# The press under which no chip may saturate, in the design and the Monte Carlo's yield
# (saturation_force's lower limit): a firm touch, fifty times the paper's 0.1 N.
SATURATION_PRESS = 5.0  # N

# eFlesh (Pattabiraman et al. 2025), its abstract's figures: a learned model's test-set RMSEs
# of the contact's position and of the normal and shear forces (the model a two-layer network,
# the authors' eFlesh repository's README says).
EFLESH_LOCALISATION = 0.5 * mm
EFLESH_NORMAL = 0.27  # N
EFLESH_SHEAR = 0.12  # N
# The eFlesh-like skin: the example spec (a 6 mm lattice of assumed effective moduli carrying
# nine 1 mm cubes of 1.3 T at 10 mm pitch, pressed by a 5 mm sphere with 0.5 N and 0.1 N of
# shear), its chips moved to the 5X board's: the authors' eFlesh repository (its README)
# reads eFlesh with the rigid magnetometer boards of ReSkin and AnySkin, prints the lattice
# in TPU 95A and carries N52 discs 3/8 inch across and 1/8 inch thick.
EFLESH_SPEC = pathlib.Path(__file__).resolve().parents[1] / "examples" / "eflesh.toml"
INCH = 25.4 * mm
EFLESH_DISC = (3 / 8 * INCH, 1 / 8 * INCH)  # m: the published magnets' diameter and thickness

PITCHES = {True: (6 * mm, 7 * mm, 8 * mm), False: (5 * mm, 6 * mm, 7 * mm, 8 * mm, 9 * mm)}
THICKNESSES = {True: (2 * mm, 3 * mm), False: (1.5 * mm, 2 * mm, 2.5 * mm, 3 * mm)}
# The linear field's nodes (the default for chips 1 mm deep under a 20 mm skin) and the map:
# quick mode checks the pipeline only (its 2 x 2 map holds only the corners of the chips'
# box). At these nodes the bounds are within 0.5 % of a twice finer resolution's
# (docs/skins.md), and the field's lattice periods (the sweep's thickest layer's) leave them
# as they are; half as many nodes across move the field's change by about 1 % and the
# worst-case bounds, which hang on the smallest signals, by 10 %.
RESOLUTION = (40, 40, 6)
MAP_GRID = {True: (2, 2), False: (5, 5)}
SAMPLES = {True: 8, False: 40}
# The sweep's cells whose spreads are computed (a forward-mode Jacobian each): two corners in quick
# mode, the two extreme corners in full mode (ReSkin's own is computed at the board's chips)
SPREAD_CELLS = {
    True: ((6 * mm, 2 * mm), (8 * mm, 3 * mm)),
    False: ((5 * mm, 1.5 * mm), (9 * mm, 3 * mm)),
}
SEED = 0

OUTPUTS = (
    "force_resolution_normal",
    "force_resolution_shear",
    "localisation_worst",
    "localisation_median",
    "crosstalk",
    "background_force_error",
    "saturation_ratio",
    "saturation_force",
)


def board_chips() -> np.ndarray:
    """The board's chip centres (5, 2) (m), relative to U1 (the middle chip)."""
    mil = np.asarray(BOARD_CHIPS_MIL)
    return (mil - mil[0]) * MIL


def cross(pitch: float) -> np.ndarray:
    """Five chips (5, 2) (m) in the board's cross (middle, +x, -x, +y, -y) at ``pitch`` (m)."""
    return pitch * np.array([[0, 0], [1, 0], [-1, 0], [0, 1], [0, -1]], dtype=float)


def skin_spec(chips, *, quick: bool, normal: float = DETECTED_FORCE, contact=(0.0, 0.0)) -> dict:
    """ReSkin's spec: the assumed skin over ``chips`` (5, 2) (m), pressed at ``contact`` (m)
    from 0 to ``normal`` (N)."""
    return {
        "scene": {"effects": ["background", "saturation"], "background": list(EARTH)},
        "magnet": {
            "shape": "skin",
            "polarization": f"{POLARIZATION} T",
            "direction": [0, 0, 1],
            "resolution": list(RESOLUTION),
        },
        "mechanics": {
            "model": "bonded_layer",
            "thickness": f"{THICKNESS} m",
            "size": [f"{SKIN_SIDE} m", f"{SKIN_SIDE} m"],
            "shear_modulus": f"{SHEAR_MODULUS} Pa",
            "poisson_ratio": POISSON,
        },
        "indenter": {"radius": f"{SPHERE} m"},
        "sensor": {
            "model": "hall3d",
            "preset": "MLX90393",
            "chips": [[f"{x} m", f"{y} m"] for x, y in np.asarray(chips)],
            "depth": f"{DEPTH} m",
            "map_grid": list(MAP_GRID[quick]),
        },
        "load": {
            "normal": ["0 N", f"{normal} N"],
            "contact_x": [f"{contact[0]} m"] * 2,
            "contact_y": [f"{contact[1]} m"] * 2,
            "points": 2,
        },
    }


def design_spec(chips, *, quick: bool, target: float) -> dict:
    """The spec of the design: the skin's J0 for a normal-force bound of ``target`` (N) at
    the same chips and thickness, with no chip saturating at rest, at 0.1 N or under a
    press of SATURATION_PRESS."""
    spec = skin_spec(chips, quick=quick)
    low, high = DESIGN_BOUNDS
    spec["design"] = {
        "variables": {"magnet.polarization": {"lower": low, "upper": high}},
        "targets": {"force_resolution_normal": f"{target} N"},
        "limits": {"saturation_ratio": {"upper": 1}, "saturation_force": {"lower": f"{SATURATION_PRESS} N"}},
    }
    return spec


def tolerance_spec(chips, *, quick: bool) -> dict:
    """ReSkin's skin with the tolerances of J0 and the chips' placement; the yield's limits
    are the paper's figures (a 3-sigma detection of 0.1 N, a 1 mm localisation); every
    output reported, so that the Monte Carlo gives each."""
    spec = skin_spec(chips, quick=quick)
    low, high = DESIGN_BOUNDS
    spec["design"] = {
        "variables": {"magnet.polarization": {"lower": low, "upper": high}},
        "limits": {
            "force_resolution_normal": {"upper": f"{DETECTED_FORCE / DETECTION_SIGMAS} N"},
            "localisation_worst": {"upper": f"{LOCALISATION} m"},
            "saturation_ratio": {"upper": 1},
            "saturation_force": {"lower": f"{SATURATION_PRESS} N"},
        },
        "tolerances": {"magnet.polarization": POLARIZATION_TOLERANCE, "placement": PLACEMENT_TOLERANCE},
        "report": list(OUTPUTS),
    }
    return spec


def shared_grid(scene, thicknesses) -> SpectralGrid:
    """One wavevector lattice for every thickness swept: the thickest layer's periods (the
    most padding), cut at the nodes' own wavenumbers as at every thickness, so that a single
    compiled scene structure serves the whole sweep."""
    return linear_grid(scene.size, max(thicknesses), scene.resolution)


evaluate = eqx.filter_jit(outputs)
first_order_parts = eqx.filter_jit(first_order)


def plain(values: dict) -> dict:
    """{name: Python float} of a dict of scalar arrays."""
    return {name: float(value) for name, value in values.items()}


def eflesh_spec(chips) -> dict:
    """The eFlesh-like skin: examples/eflesh.toml with its chips at ``chips`` (5, 2) (m), the
    5X board's (the board eFlesh reads); every other table as the example's."""
    spec = load_spec(EFLESH_SPEC)
    spec["sensor"]["chips"] = [[f"{x} m", f"{y} m"] for x, y in np.asarray(chips)]
    return spec


def eflesh(chips) -> dict:
    """The eFlesh-like skin over ``chips`` (5, 2) (m), at the example's sweep: its outputs
    (SI; the bounds at the sweep's largest load, worst and median over the example's map),
    that load's normal force ``press`` and ``shear`` (F_x, F_y) (N), its Hertz ``contact_radius``
    (m), and the example's layer, magnets and map as the report states them (SI)."""
    spec = eflesh_spec(chips)
    scene, loads = scene_from_spec(spec), loads_from_spec(spec)
    largest = int(np.argmax(loads.normal))
    press = float(loads.normal[largest])
    return {
        "outputs": plain(evaluate(scene, loads)),
        "press": press,
        "shear": [float(f) for f in loads.shear[largest]],
        "contact_radius": float(scene.contact_radius(press)),
        "sphere_radius": float(scene.sphere_radius),
        "thickness": float(scene.thickness),
        "shear_modulus": float(scene.shear_modulus),
        "poisson_ratio": float(scene.poisson_ratio),
        "magnets": int(scene.magnets.centres.shape[0]),
        "magnet_side": float(scene.magnets.sizes[0, 0]),
        "polarization": float(scene.polarization),
        "map_grid": list(scene.map_grid),
    }


def spreads(tp, scene) -> dict:
    """{output: {"total": first-order standard deviation, group: its part}} (SI) of
    ``scene``'s outputs under the tolerances of ``tp``, the parts by group of variates
    ("magnet.polarization", "placement.x": every chip's x, ...) in quadrature: the library's
    first-order parts (magdesign.design.tolerance.first_order, forward-mode derivatives along
    each variate), through one compiled program that every cell of the sweep shares."""
    _, parts = first_order_parts(tp, scene)
    result = {}
    for name in OUTPUTS:
        squares = {}
        for label, part in zip(tp.labels, np.asarray(parts[name])):
            squares[label] = squares.get(label, 0.0) + float(part) ** 2
        result[name] = {"total": math.sqrt(sum(squares.values())), **{k: math.sqrt(v) for k, v in squares.items()}}
    return result


def sampled(tp, samples: int) -> dict:
    """The library's Monte Carlo of the tolerances at ReSkin's J0
    (magdesign.design.tolerance.monte_carlo, seed SEED): each output's mean and standard
    deviation, and the yield against the design's limits (the paper's figures)."""
    run = monte_carlo(tp, {"magnet.polarization": POLARIZATION}, samples=samples, seed=SEED, progress=False)
    return {
        "samples": run.samples,
        "seed": run.seed,
        "yield": run.yield_fraction,
        "yield_stderr": run.yield_stderr,
        "outputs": {name: {"mean": run.outputs[name]["mean"], "std": run.outputs[name]["std"]} for name in OUTPUTS},
    }


def sweep(tp, scene, loads, quick: bool) -> list[dict]:
    """The outputs and their first-order spreads under the tolerances (SI) at every pitch
    and thickness: the same compiled structure, the chips moved and h a parameter."""
    rows = []
    for pitch in PITCHES[quick]:
        at_pitch = dataclasses.replace(scene, chips=cross(pitch))
        for thickness in THICKNESSES[quick]:
            cell = with_parameters(at_pitch, {"mechanics.thickness": thickness})
            values = plain(evaluate(cell, loads))
            spread = spreads(tp, cell) if (pitch, thickness) in SPREAD_CELLS[quick] else None
            rows.append({"pitch": pitch, "thickness": thickness, **values, "sigma": spread})
            progress(f"pitch {pitch / mm:g} mm, thickness {thickness / mm:g} mm")
    return rows


def main(argv=None):
    args = arguments(NAME, argv, __doc__, plot=True)
    quick = args.quick
    report = Report(
        NAME, "ReSkin: a magnetised skin over five MLX90393 chips (Bhirangi et al. 2021)", args.out, quick, BANNER
    )
    chips = board_chips()
    pitch = float(np.mean(np.linalg.norm(chips[1:], axis=1)))
    # the skin with its tolerances' effects (placement, at zero: the same outputs), on the
    # sweep's lattice: one scene structure, compiled once, for every evaluation below
    tp = tolerance_problem_from_spec(tolerance_spec(chips, quick=quick))
    grid = shared_grid(tp.scene, THICKNESSES[quick] + (THICKNESS,))
    scene, loads = dataclasses.replace(tp.scene, spectral=grid), tp.loads

    progress("ReSkin's skin at the board's chips, pressed with 0.1 N (compiles the outputs' Jacobians)")
    base = plain(evaluate(scene, loads))
    contact_radius = float(scene.contact_radius(DETECTED_FORCE))
    # the readings are linear in J0: the largest of them reaches the range at J0 / ratio (the
    # Earth's field aside)
    j0_saturating = POLARIZATION / base["saturation_ratio"]
    # the press at which the Hertz patch reaches a / h = 0.5 (a grows as F^(1/3))
    reach = DETECTED_FORCE * (0.5 * THICKNESS / contact_radius) ** 3
    base_spread = spreads(tp, scene)

    progress("the sweep of pitch and thickness")
    rows = sweep(tp, scene, loads, quick)
    progress(f"Monte Carlo of the tolerances at ReSkin's design ({SAMPLES[quick]} samples)")
    mc = sampled(dataclasses.replace(tp, scene=scene), SAMPLES[quick])

    progress(
        "the design: half ReSkin's normal-force bound with the same chips, no chip saturating (compiles derivatives)"
    )
    target = base["force_resolution_normal"] / 2
    problem, _ = problem_from_spec(design_spec(chips, quick=quick, target=target))
    answer = solve(problem)
    designed = plain(evaluate(with_parameters(scene, dict(answer.parameters)), loads))

    progress("the eFlesh-like skin over the board's chips (compiles its outputs)")
    skin = eflesh(chips)

    report.comparison(comparison_rows(base, pitch, contact_radius))
    report.heading("Assumptions")
    report.text(
        "The paper's summary figures and the board's files fix the chips (five MLX90393, their positions) and the "
        "skin's thickness range; nothing at hand gives the rest, which is assumed: "
        f"a skin {THICKNESS / mm:g} mm thick (the thinner end of 2-3 mm) and {SKIN_SIDE / mm:g} mm square (the board's "
        f"sensing square, {BOARD_SIDE / mm:.3g} mm in its outline), shear modulus {SHEAR_MODULUS / 1e3:g} kPa and "
        f"Poisson's ratio {POISSON:g} (a soft, nearly incompressible silicone), polarisation J0 = {POLARIZATION / mT:g} mT "
        f"through the thickness (the particles' loading and magnetisation), the chips' Hall plates {DEPTH / mm:g} mm below "
        f"the skin, a sphere of radius {SPHERE / mm:g} mm as the indenter, the Earth's 50 uT along z, and the chips' noise "
        f"{NOISE_NOTE}: the MLX90393 at GAIN_SEL = 7, RES_XYZ = 0, the board firmware library's setting (its "
        "datasheet's RMS noise at that setting is not in the copies at hand). Every bound below scales as 1 / J0 and "
        "as the noise; the tolerances (J0 "
        f"{POLARIZATION_TOLERANCE}, each chip's placement {PLACEMENT_TOLERANCE} per axis) are assumed too."
    )
    report.text(
        f"The layer's linear field at {RESOLUTION} nodes (across, across, through), the bounds' map {MAP_GRID[quick]} contact positions over the chips' "
        f"bounding box. {QUICK_NOTE if quick else FULL_NOTE}"
    )

    report.heading("The bounds at 0.1 N")
    report.text(
        f"Hertz's contact radius of the {SPHERE / mm:g} mm sphere at 0.1 N is {contact_radius / mm:.3g} mm, "
        f"a / h = {contact_radius / THICKNESS:.2g}: within the half-space patch's reach (about 0.5). "
        f"At rest and at 0.1 N the largest chip reading is {base['saturation_ratio']:.3g} of the chip's range "
        "(saturation_ratio): the skin's own field at the chips and the Earth's. "
        + saturation_text(base["saturation_force"], reach)
        + f" The skin's field at rest saturates a chip once J0 passes about {j0_saturating / mT:.3g} mT (J0 / "
        f"saturation_ratio, the Earth's 50 uT aside), where the normal-force bound would be "
        f"{base['force_resolution_normal'] * POLARIZATION / j0_saturating / mN:.3g} mN."
    )
    report.table(["output", "value", "unit"], [[name, base[name], UNITS[name]] for name in OUTPUTS])

    report.heading("Pitch and thickness, with the tolerances")
    report.text(
        "The chips in the board's cross at each pitch, the skin at each thickness, pressed with 0.1 N; '+-' is the "
        f"first-order standard deviation under the tolerances (J0 {POLARIZATION_TOLERANCE}, each chip's placement "
        f"{PLACEMENT_TOLERANCE} per axis), from the derivative along each variate "
        f"(at the sweep's cells {', '.join(f'({p / mm:g}, {h / mm:g}) mm' for p, h in SPREAD_CELLS[quick])})."
    )
    report.table(SWEEP_HEADERS, [sweep_cells(row) for row in rows])
    near = [row for row in rows if SKIN_SIDE / 2 - row["pitch"] < row["thickness"]]
    if near:
        cells = ", ".join(f"({row['pitch'] / mm:g}, {row['thickness'] / mm:g})" for row in near)
        report.text(
            f"At (pitch, thickness) = {cells} mm the map's corners lie within a thickness of the {SKIN_SIDE / mm:g} mm "
            "skin's side, where the unbounded layer's mechanics leaves its reach (docs/skins.md): those rows are rough."
        )
    best = min(rows, key=lambda row: row["force_resolution_normal"])
    report.text(
        f"The finest normal-force bound of the sweep is {best['force_resolution_normal'] / mN:.3g} mN at a pitch of "
        f"{best['pitch'] / mm:g} mm and a {best['thickness'] / mm:g} mm skin; ReSkin's (the board's chips, "
        f"{THICKNESS / mm:g} mm) is {base['force_resolution_normal'] / mN:.3g} mN."
    )
    report.text(
        "At ReSkin's design the spreads' parts (first order, SI): "
        + "; ".join(
            f"{name}: " + ", ".join(f"{key} {value:.3g}" for key, value in base_spread[name].items())
            for name in ("force_resolution_normal", "localisation_worst", "saturation_ratio")
        )
        + ". The readings are linear in J0, so J0's part of every bound is its relative tolerance times the bound."
    )
    report.text(
        f"Monte Carlo of the tolerances at ReSkin's design ({mc['samples']} samples, seed {mc['seed']}): the yield "
        f"against the paper's figures (a {DETECTION_SIGMAS:g}-sigma detection of 0.1 N, localisation within 1 mm, no "
        f"chip saturating at rest, at 0.1 N or under a {SATURATION_PRESS:g} N press) is {mc['yield']:.3g} +- {mc['yield_stderr']:.2g}."
    )
    report.table(
        ["output", "nominal", "mean (samples)", "std (samples)", "std (first order)", "unit"],
        [
            [name, base[name], o["mean"], o["std"], base_spread[name]["total"], UNITS[name]]
            for name, o in mc["outputs"].items()
        ],
    )
    if args.plot:
        figure(report, rows)

    report.heading("A design that halves ReSkin's normal-force bound")
    report.text(
        f"Target: force_resolution_normal = {target / mN:.4g} mN (half of ReSkin's), the same chips and thickness, no "
        f"chip saturating (saturation_ratio <= 1, and saturation_force >= {SATURATION_PRESS:g} N: no press up to "
        f"{SATURATION_PRESS:g} N saturates a chip); variable J0 in [{DESIGN_BOUNDS[0]}, {DESIGN_BOUNDS[1]}]. The solver's "
        f"status: {answer.status}; J0 = {answer.parameters['magnet.polarization'] / mT:.4g} mT. Checked with the "
        f"sweep's scene: force_resolution_normal = {designed['force_resolution_normal'] / mN:.4g} mN, saturation_ratio "
        f"= {designed['saturation_ratio']:.3g}, saturation_force = {designed['saturation_force']:.4g} N, background_force_error = {designed['background_force_error']:.3g} N. "
        "The readings are linear in J0, so every bound scales as 1 / J0: the answer is twice ReSkin's J0, which the "
        "skin's particle loading or magnetising field would have to give."
    )
    eflesh_section(report, skin, chips)

    report.result(
        "published",
        {
            "detected_force": DETECTED_FORCE,
            "localisation": LOCALISATION,
            "thickness_range": THICKNESS_RANGE,
            "chips": CHIPS,
        },
    )
    report.result(
        "assumptions",
        {
            "thickness": THICKNESS,
            "shear_modulus": SHEAR_MODULUS,
            "poisson_ratio": POISSON,
            "polarization": POLARIZATION,
            "depth": DEPTH,
            "sphere_radius": SPHERE,
            "skin_side": SKIN_SIDE,
            "resolution": RESOLUTION,
            "map_grid": MAP_GRID[quick],
        },
    )
    report.result("chips", chips)
    report.result("pitch", pitch)
    report.result("board_side", BOARD_SIDE)
    report.result("contact_radius", contact_radius)
    report.result("outputs", base)
    report.result("units", {name: UNITS[name] for name in OUTPUTS})
    report.result(
        "saturation",
        {
            "force": base["saturation_force"],
            "cap": SATURATION_FORCE_CAP,
            "ratio": base["saturation_ratio"],
            "polarization": j0_saturating,
            "reach": reach,
        },
    )
    report.result("sweep", rows)
    report.result(
        "eflesh",
        {
            "published": {"localisation": EFLESH_LOCALISATION, "normal": EFLESH_NORMAL, "shear": EFLESH_SHEAR},
            **skin,
        },
    )
    report.result("spread", base_spread)
    report.result("monte_carlo", mc)
    report.result(
        "design",
        {"status": answer.status, "target": target, "parameters": dict(answer.parameters), "checked": designed},
    )
    report.write()


# Quick mode's banner: what it shares with full mode and what it leaves out.
BANNER = (
    f"the field at full mode's resolution, {RESOLUTION} nodes; a {MAP_GRID[True][0]} x {MAP_GRID[True][1]} map of "
    f"contact positions, the corners of the chips' box (full mode's is {MAP_GRID[False][0]} x {MAP_GRID[False][1]}), "
    f"a {len(PITCHES[True])} x {len(THICKNESSES[True])} sweep and {SAMPLES[True]} Monte Carlo samples; the "
    "eFlesh-like skin as in full mode."
)
QUICK_NOTE = (
    "Quick mode checks the study's pipeline: its field is full mode's, but its 2 x 2 map holds only the corners of "
    "the chips' box (at ReSkin's design the worst bounds lie there too), and its sweep and Monte Carlo are small."
)
FULL_NOTE = (
    "The field is the layer's linear field (first order in the displacement), converged: at ReSkin's design (5 x 5 "
    "map) the worst normal-force bound is 82.1 mN at these nodes and 82.5 mN at twice as many across and 10 through, "
    "the worst localisation 2.03 mm at both, the median 0.80 mm (docs/skins.md). The rigid cells used before gave "
    "10.7 mN, 44 mN and 0.28 N at cells (4, 4, 2), (8, 8, 6) and (12, 12, 6), and medians of 47-67 um: they had "
    "not converged. The crosstalk "
    "column says how nearly the normal force and the shear are confounded at the map's worst point."
)
UNITS = {
    "force_resolution_normal": "N",
    "force_resolution_shear": "N",
    "localisation_worst": "m",
    "localisation_median": "m",
    "crosstalk": "1",
    "background_force_error": "N",
    "saturation_ratio": "1",
    "saturation_force": "N",
}
SWEEP_HEADERS = [
    "pitch (mm)",
    "thickness (mm)",
    "normal force (mN)",
    "shear force (mN)",
    "localisation worst (um)",
    "localisation median (um)",
    "crosstalk",
    "Earth's field (N)",
    "saturation ratio",
    "saturation force (N)",
]


def sweep_cells(row) -> list:
    """One row of the sweep's table in the headers' units: value +- first-order spread where computed."""

    def cell(name, scale):
        spread = "" if row["sigma"] is None else f" +- {row['sigma'][name]['total'] / scale:.2g}"
        return f"{row[name] / scale:.3g}{spread}"

    return [
        row["pitch"] / mm,
        row["thickness"] / mm,
        cell("force_resolution_normal", mN),
        cell("force_resolution_shear", mN),
        cell("localisation_worst", 1e-6),
        cell("localisation_median", 1e-6),
        row["crosstalk"],
        cell("background_force_error", 1.0),
        cell("saturation_ratio", 1.0),
        cell("saturation_force", 1.0),
    ]


def comparison_rows(base, pitch, contact_radius) -> list[dict]:
    """The report's first table: the paper's figures beside the model's bounds at 0.1 N."""
    detect = DETECTION_SIGMAS * base["force_resolution_normal"]
    bound = "a Cramer-Rao bound: a floor for any unbiased reader of these chips, with the assumed noise and J0 (it scales as noise / J0)"
    return [
        {
            "quantity": "smallest detected normal force",
            "published": "0.1 N",
            "source": "summary",
            "magdesign": f"{detect * 1e3:.3g} mN ({DETECTION_SIGMAS:g} sigma of Fn, worst over the map, at 0.1 N)",
            "difference": f"x{detect / DETECTED_FORCE:.2g}",
            "why": f"{bound}; the paper's 0.1 N is what its learned model resolved, with drift, hysteresis and the chips' real noise in it",
        },
        {
            "quantity": "contact localisation",
            "published": "about 1 mm",
            "source": "summary",
            "magdesign": f"{base['localisation_worst'] / 1e-6:.3g} um worst, {base['localisation_median'] / 1e-6:.3g} um median (at 0.1 N)",
            "difference": f"x{base['localisation_worst'] / LOCALISATION:.2g} (worst)",
            "why": f"{bound}; the paper's 1 mm is a learned model's test-set error over its probes and forces, its model error included",
        },
        {
            "quantity": "skin thickness",
            "published": "2-3 mm",
            "source": "summary",
            "magdesign": f"{THICKNESS / mm:g} mm (swept 1.5-3 mm)",
            "difference": "within",
            "why": "the thinner end is assumed; the sweep's table covers the range",
        },
        {
            "quantity": "chips",
            "published": "5 MLX90393",
            "source": "summary; the board's pick-and-place file",
            "magdesign": f"5 MLX90393 in a cross at {pitch / mm:.3g} mm pitch",
            "difference": "none",
            "why": "read from the board's files (the example spec's 10 mm cross is not the board's)",
        },
        {
            "quantity": "normal / shear force resolution (1 sigma)",
            "published": "not stated",
            "source": "-",
            "magdesign": f"{base['force_resolution_normal'] * 1e3:.3g} / {base['force_resolution_shear'] * 1e3:.3g} mN",
            "difference": "-",
            "why": "the paper reports a learned model's errors, not a noise-equivalent force",
        },
        {
            "quantity": "Earth's field as a normal-force error",
            "published": "not stated",
            "source": "-",
            "magdesign": f"{base['background_force_error']:.3g} N per 50 uT",
            "difference": "-",
            "why": "a learned model trained on one place's field absorbs it as an offset; turned or moved, the skin reads it as force",
        },
        {
            "quantity": "Hertz contact radius at 0.1 N",
            "published": "not stated",
            "source": "-",
            "magdesign": f"{contact_radius / mm:.3g} mm",
            "difference": "-",
            "why": "the assumed sphere and modulus",
        },
    ]


def saturation_text(force: float, reach: float) -> str:
    """The report's sentence on ``saturation_force`` (N) at ReSkin's design; ``reach`` (N): the
    press at which the Hertz patch leaves the layer's reach (a / h = 0.5)."""
    if force >= SATURATION_FORCE_CAP:
        return (
            f"No press up to {SATURATION_FORCE_CAP / 1e3:g} kN saturates a chip: saturation_force, the largest press "
            "(at the sweep's shear ratio, over every point of the map and the sweep's contact) before some chip "
            f"axis reaches its range, is its cap. The Hertz patch leaves the layer's reach near {reach:.2g} N "
            "(a / h = 0.5), so the cap says only that the linear layer's press moves the readings by a small part of "
            "the range, not that a real skin pressed that hard keeps its chips in range."
        )
    return (
        f"A press of {force:.3g} N saturates a chip (saturation_force: the largest press at the sweep's shear ratio, "
        "worst over the map and the sweep's contact, before some chip axis reaches its range)"
        + (
            f", past the Hertz patch's reach near {reach:.2g} N (a / h = 0.5): an estimate of its order."
            if force > reach
            else "."
        )
    )


def eflesh_section(report, skin: dict, chips) -> None:
    """The report's section on the eFlesh-like skin: its bounds beside eFlesh's published RMSEs."""
    out = skin["outputs"]
    bound = (
        "a Cramer-Rao bound at the example's press: a noise floor for any unbiased reader of these chips, not the RMSE "
        "of a learned model over a test set"
    )
    learned = "eFlesh's figure is a two-layer network's RMSE over its probe's test set, its model error, the lattice's hysteresis and drift in it"
    disc_volume = math.pi * (EFLESH_DISC[0] / 2) ** 2 * EFLESH_DISC[1]
    rows = [
        {
            "quantity": "contact localisation",
            "published": "0.5 mm RMSE",
            "source": "abstract",
            "magdesign": f"{out['localisation_worst'] / 1e-6:.3g} um worst, {out['localisation_median'] / 1e-6:.3g} um median",
            "difference": f"x{out['localisation_worst'] / EFLESH_LOCALISATION:.2g} (worst)",
            "why": f"{bound}; {learned}",
        },
        {
            "quantity": "normal force",
            "published": "0.27 N RMSE",
            "source": "abstract",
            "magdesign": f"{out['force_resolution_normal'] / mN:.3g} mN (1 sigma, worst over the map)",
            "difference": f"x{out['force_resolution_normal'] / EFLESH_NORMAL:.2g}",
            "why": f"{bound}; {learned}, over its whole range of forces",
        },
        {
            "quantity": "shear force",
            "published": "0.12 N RMSE",
            "source": "abstract",
            "magdesign": f"{out['force_resolution_shear'] / mN:.3g} mN (1 sigma, the worse axis, worst over the map)",
            "difference": f"x{out['force_resolution_shear'] / EFLESH_SHEAR:.2g}",
            "why": f"{bound}; {learned}",
        },
        {
            "quantity": "chips",
            "published": "ReSkin's and AnySkin's boards",
            "source": "the authors' repository",
            "magdesign": f"5 MLX90393 in the 5X board's cross ({np.linalg.norm(chips[1]) / mm:.3g} mm pitch)",
            "difference": "none",
            "why": "the example's 10 mm cross moved to the board's chips",
        },
        {
            "quantity": "magnets",
            "published": 'N52 discs 3/8" across, 1/8" thick',
            "source": "the authors' repository",
            "magdesign": f"{skin['magnets']} cubes of {skin['magnet_side'] / mm:g} mm, {skin['polarization']:g} T (the example's)",
            "difference": f"x{disc_volume / skin['magnet_side'] ** 3:.3g} in volume",
            "why": "assumed: the magnets' number and places in eFlesh's lattice are not in the sources at hand; a disc's larger "
            "moment gives larger signals and smaller bounds where the chips' range allows it (the bounds scale as 1 / J)",
        },
        {
            "quantity": "lattice",
            "published": "printed TPU 95A cut-cell microstructure",
            "source": "abstract; the authors' repository",
            "magdesign": f"an effective layer {skin['thickness'] / mm:g} mm thick, shear modulus "
            f"{skin['shear_modulus'] / 1e3:g} kPa, Poisson's ratio {skin['poisson_ratio']:g}",
            "difference": "assumed",
            "why": "the lattice's homogenised moduli are assumed (the example's); the magnets' stiffening of the lattice "
            "around them is left out",
        },
    ]
    report.heading("An eFlesh-like skin")
    report.text(
        "eFlesh (Pattabiraman et al. 2025) carries discrete magnets in a printed soft lattice over the same kind of "
        "board. The skin scene serves it: the lattice is an effective elastic layer, the magnets cuboids that move "
        "and turn with it (docs/skins.md). The skin is `examples/eflesh.toml` with its chips moved to the 5X board's, "
        f"pressed as the example is (up to {skin['press']:g} N with a shear of ({skin['shear'][0]:g}, "
        f"{skin['shear'][1]:g}) N by a sphere of radius {skin['sphere_radius'] / mm:g} mm; Hertz's contact radius "
        f"{skin['contact_radius'] / mm:.3g} mm, a / h = {skin['contact_radius'] / skin['thickness']:.2g}), its bounds "
        f"worst and median over the example's {skin['map_grid'][0]} x {skin['map_grid'][1]} map of the chips' box, the "
        "chips' noise one LSB per axis."
    )
    report.table(
        ["quantity", "published", "source", "magdesign", "difference", "why"],
        [[r["quantity"], r["published"], r["source"], r["magdesign"], r["difference"], r["why"]] for r in rows],
    )
    published = {
        "localisation_worst": EFLESH_LOCALISATION,
        "force_resolution_normal": EFLESH_NORMAL,
        "force_resolution_shear": EFLESH_SHEAR,
    }
    above = [name for name, value in published.items() if out[name] >= value]
    report.text(
        (
            "Every bound lies below eFlesh's learned error: with these assumptions the chips' noise alone would not "
            "limit eFlesh's figures, which a learned model's error, the lattice's hysteresis and drift can. "
            if not above
            else f"The bounds of {', '.join(above)} lie above eFlesh's learned errors: the assumed magnets and "
            "lattice give smaller signals than eFlesh's own. "
        )
        + f"Over the example's loads the largest chip reading is {out['saturation_ratio']:.2g} of the chips' range, "
        "and "
        + (
            f"no press up to {SATURATION_FORCE_CAP / 1e3:g} kN saturates a chip."
            if out["saturation_force"] >= SATURATION_FORCE_CAP
            else f"a press of {out['saturation_force']:.3g} N saturates one (saturation_force): magnets of "
            f"{skin['polarization']:g} T a few millimetres above the chips take a good part of the range, and "
            "eFlesh's discs, of far larger moment, would take more unless they sit farther from the chips or the "
            "chips' gain is coarser."
        )
    )
    report.table(["output", "value", "unit"], [[name, out[name], UNITS[name]] for name in OUTPUTS])


def figure(report, rows) -> None:
    """The normal-force bound against thickness, one line per pitch (only with --plot)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axis = plt.subplots(figsize=(6.0, 3.6))
    for pitch in sorted({row["pitch"] for row in rows}):
        mine = [row for row in rows if row["pitch"] == pitch]
        axis.plot(
            [r["thickness"] / mm for r in mine],
            [r["force_resolution_normal"] / mN for r in mine],
            marker="o",
            label=f"{pitch / mm:g} mm",
        )
    axis.set_xlabel("skin thickness (mm)")
    axis.set_ylabel("normal-force bound (mN)")
    axis.legend(title="pitch", fontsize=8)
    report.figure(
        fig,
        "sweep.png",
        "The normal-force bound at 0.1 N against the skin's thickness, per chip pitch "
        "(the table gives the tolerances' spreads)",
    )


if __name__ == "__main__":
    main()
