"""The one table of spec keys: every key a spec may hold, with what it means.

Each :class:`~magdesign.spec.key.Key` gives its table and name (dotted: ``mechanics.thickness``; the tables of a
``[[soft]]`` or ``[[magnet.extra]]`` array are ``soft`` and ``magnet.extra``; a ``*`` stands
for a name the spec chooses, as a design variable's parameter), its type, SI unit, default,
physical domain, plausible range for a plain number, presets and a one-line meaning.

The readers (:mod:`magdesign.spec.scene`, :mod:`magdesign.scene.loads`,
:mod:`magdesign.spec.design`, :mod:`magdesign.spec.tolerance`) look every key up here
(:func:`magdesign.spec.checks.lookup`): a key read in code and missing from this table, or
read as another type, unit or default than the table gives, raises
:class:`~magdesign.spec.checks.UnlistedKeyError` (a programming error, never a bad spec). The spec reference (:mod:`magdesign.spec.reference`) is rendered from it.

A plain number (no unit string) is SI. Outside its key's plausible range it is read all the
same, with a :class:`~magdesign.spec.checks.PlausibilityWarning` naming the key and the unit it was read in
(``mechanics.thickness = 3 was read as 3 m; write "3 mm" for millimetres``). A value with a
unit far outside real parts (a remanence above NdFeB's) warns too.
"""

from magdesign.spec.key import (
    ANGLE,
    AREA,
    FIELD,
    FORCE,
    LENGTH,
    MODULUS,
    NONNEGATIVE,
    POSITIVE,
    READING,
    READING_PLAUSIBLE,
    REQUIRED,
    TIME,
    VOLTAGE,
    Depends,
    Key,
)
from magdesign.transducers import ak8963, inesc_spin_valve, mlx90393, nve_aa003, panasonic_meander
from magdesign.units import deg

_NDFEB = (1.6, "the strongest permanent magnets (NdFeB) reach about 1.5 T")
_EFFECTS = {
    "temperature_drift": "the magnet's remanence drifts with temperature (temperature_coefficient, temperature_change)",
    "placement": "every sensor placed off its nominal position (placement)",
    "chip_tilt": "every chip tilted off its nominal orientation (tilt)",
    "viscoelastic_lag": "the elastomer follows the load with a first-order lag (lag_time_constant)",
    "area_averaging": "each chip reads the field averaged over its active area (area, quadrature)",
    "background": "a uniform background field is added (background)",
    "saturation": "each reading clips at the chip's range (saturation_limit)",
    "noise": "Gaussian noise on each reading (noise)",
    "quantisation": "each reading rounded to the converter's step (lsb)",
}
_SENSOR_PRESETS = {
    "AK8963": ("hall3d: AKM AK8963 3-axis Hall sensor, 16-bit output", ak8963),
    "MLX90393": ("hall3d: Melexis MLX90393 3-axis Hall sensor at its finest setting", mlx90393),
    "INESC": ("spin_valve: INESC-MN chip of six spin valves in series", inesc_spin_valve),
    "PANASONIC": ("spin_valve, gmr: Panasonic GMR meander at a 0.6 V bias", panasonic_meander),
    "AA003-02": ("gmr: NVE AA003-02 GMR bridge at a 5 V supply", nve_aa003),
}
_POSE = {
    "aligned": "every chip's axes along the scene's x, y, z",
    "radial": "each chip's sensitive axis along the outward radius from the scene's axis",
}


def _keys():
    q, R, D = "quantity", REQUIRED, Depends
    return [
        # [scene]: the effects of the reading chain and their options
        Key(
            "scene.effects",
            "names",
            "the effects the measurement chain applies, in the chain's order",
            default=[],
            choices=_EFFECTS,
        ),
        Key(
            "scene.temperature_coefficient",
            q,
            "the reversible temperature coefficient of the remanence",
            "1/K",
            -0.12e-2,
            plausible=(0.0, 0.1),
        ),
        Key(
            "scene.temperature_change",
            q,
            "the magnet's temperature change from where its remanence is given",
            "K",
            10.0,
            plausible=(0.0, 500.0),
        ),
        Key(
            "scene.placement",
            "quantities",
            "each sensor's offset from its nominal position (x, y, z)",
            "m",
            [200e-6, 0.0, 0.0],
            plausible=LENGTH,
            length=3,
        ),
        Key(
            "scene.tilt",
            "quantities",
            "each chip's tilt angles (alpha, beta, gamma) after its nominal rotation",
            "rad",
            [10.0 * deg, 0.0, 0.0],
            plausible=ANGLE,
            length=3,
        ),
        Key(
            "scene.lag_time_constant",
            q,
            "the elastomer's first-order lag time constant",
            "s",
            D("0.505 s, the dome-Hall paper's identified lag (100 Hz pole 0.9804)"),
            POSITIVE,
            TIME,
        ),
        Key(
            "scene.area",
            "quantities",
            "a chip's active area, width along its a axis and height along b",
            "m",
            [200e-6, 95e-6],
            POSITIVE,
            LENGTH,
            length=2,
        ),
        Key("scene.quadrature", "integer", "quadrature points per side of the active area", default=3),
        Key(
            "scene.background",
            "quantities",
            "the uniform background field (x, y, z), scene frame",
            "T",
            [0.0, 0.0, 50e-6],
            plausible=FIELD,
            length=3,
        ),
        Key(
            "scene.saturation_limit",
            q,
            "where a reading clips (each axis)",
            READING,
            D("the chip's full scale (a preset's range; the 2.048 V ADC for spin valves and GMRs)"),
            POSITIVE,
            READING_PLAUSIBLE,
        ),
        Key(
            "scene.noise",
            q,
            "the standard deviation of the noise on each reading",
            READING,
            D("one LSB for a Hall chip; 3.4 uV (the 24-bit ADC's) for spin valves and GMRs"),
            NONNEGATIVE,
            READING_PLAUSIBLE,
        ),
        Key(
            "scene.lsb",
            q,
            "the quantisation step of each reading",
            READING,
            D("the chip's LSB; 2.048 V / 2^23 for spin valves and GMRs"),
            POSITIVE,
            READING_PLAUSIBLE,
        ),
        # [magnet]
        Key(
            "magnet.shape",
            "choice",
            "the permanent magnet, which picks the kind of scene",
            choices={
                "cylinder": "an axially magnetised cylinder over point sensors",
                "film": "a sinusoidally magnetised film over a grid of Hall chips",
                "plate": "a magnet plate under a soft pole in a ball (magnetic suspension)",
                "skin": "a magnetised elastomer layer over an array of 3-axis chips (a magnetic skin)",
            },
        ),
        Key("magnet.radius", q, "the cylinder's or plate's radius", "m", R, POSITIVE, LENGTH),
        Key("magnet.height", q, "the cylinder's height or the plate's thickness", "m", R, POSITIVE, LENGTH),
        Key(
            "magnet.remanence",
            q,
            "the remanence (polarisation J = mu0 M) along the magnet's axis",
            "T",
            R,
            POSITIVE,
            FIELD,
            _NDFEB,
        ),
        Key(
            "magnet.fidelity",
            "choice",
            "the cylinder's field model",
            default="exact",
            choices={
                "exact": "the exact field everywhere",
                "dipole": "the far-field dipole",
                "axis": "the closed form on the axis (every sensor on the axis)",
            },
        ),
        Key(
            "magnet.direction",
            "quantities",
            "the polarisation's direction (x, y, z), normalised (absent: the axis; a skin's: through its thickness, [0, 0, 1], or with magnet.period [0, 0, -1] at x = 0)",
            "1",
            None,
            length=3,
        ),
        Key(
            "magnet.offset",
            "quantities",
            "the magnet's offset (x, y, z) from its place on the axis",
            "m",
            None,
            plausible=LENGTH,
            length=3,
        ),
        Key(
            "magnet.rotation",
            "quantities",
            "the magnet's rotation angles (x, y, z)",
            "rad",
            None,
            plausible=ANGLE,
            length=3,
        ),
        Key("magnet.extra", "tables", "further cylinder magnets, [[magnet.extra]]", default=[]),
        Key(
            "magnet.period",
            q,
            "the film's magnetisation period (a skin's: its Halbach pattern along x; absent: uniform)",
            "m",
            R,
            POSITIVE,
            LENGTH,
        ),
        Key("magnet.thickness", q, "the film's thickness", "m", R, POSITIVE, LENGTH),
        Key("magnet.magnetization", q, "the film's polarisation amplitude J0", "T", R, POSITIVE, FIELD, _NDFEB),
        Key("magnet.periods", "integer", "the film's width in periods (absent: an infinite film)", default=None),
        Key(
            "magnet.polarization",
            q,
            "the skin's uniform polarisation J0 (from its particle loading; with [[magnet.magnets]], each magnet's)",
            "T",
            R,
            POSITIVE,
            FIELD,
            _NDFEB,
        ),
        Key(
            "magnet.field",
            "choice",
            "the uniformly magnetised skin's field model",
            default="linear",
            choices={
                "linear": "first order in the displacement, integrated over the layer (converged, with an estimate)",
                "cells": "rigid cuboid cells carried by the displacement (magnet.cells)",
            },
        ),
        Key(
            "magnet.resolution",
            "integers",
            "the linear field's nodes [along x, along y, Gauss nodes through the thickness]",
            default=D("2 nodes per chip depth across the layer, 6 Gauss nodes through it"),
            length=3,
        ),
        Key(
            "magnet.cells",
            "integers",
            'the skin\'s cuboid cells [along x, along y, through the thickness] for magnet.field = "cells"',
            default=[16, 16, 8],
            length=3,
        ),
        Key(
            "magnet.magnets",
            "tables",
            "a skin's discrete magnets, [[magnet.magnets]] (an eFlesh-like skin: the layer itself unmagnetised)",
            default=[],
        ),
        # [[magnet.magnets]]
        Key(
            "magnet.magnets.position",
            "quantities",
            "this magnet's centre (x, y, z) at rest, inside the layer (z above the board)",
            "m",
            R,
            plausible=LENGTH,
            length=3,
        ),
        Key(
            "magnet.magnets.size",
            "quantities",
            "this magnet's sides (x, y, z), a cuboid",
            "m",
            R,
            POSITIVE,
            LENGTH,
            length=3,
        ),
        Key(
            "magnet.magnets.direction",
            "quantities",
            "this magnet's polarisation direction (x, y, z), normalised (absent: magnet.direction, else z)",
            "1",
            None,
            length=3,
        ),
        # [[magnet.extra]]
        Key("magnet.extra.radius", q, "this magnet's radius", "m", R, POSITIVE, LENGTH),
        Key("magnet.extra.height", q, "this magnet's height", "m", R, POSITIVE, LENGTH),
        Key(
            "magnet.extra.polarization",
            "quantities",
            "this magnet's polarisation (x, y, z), its own frame",
            "T",
            R,
            plausible=FIELD,
            length=3,
        ),
        Key(
            "magnet.extra.position",
            "quantities",
            "this magnet's centre (x, y, z), scene frame",
            "m",
            R,
            plausible=LENGTH,
            length=3,
        ),
        Key(
            "magnet.extra.rotation",
            "quantities",
            "this magnet's rotation angles (x, y, z)",
            "rad",
            [0.0, 0.0, 0.0],
            plausible=ANGLE,
            length=3,
        ),
        Key("magnet.extra.moves", "bool", "whether this magnet moves with the main one", default=True),
        # [mechanics]
        Key(
            "mechanics.model",
            "choice",
            "what carries the magnet",
            choices={
                "dome": "a hemispherical elastomer dome pressed by a flat plate",
                "layer": "a uniform elastomer layer",
                "tilt": "a ball on a torsion spring (the pole scene)",
                "bonded_layer": "a linear elastic layer bonded to a rigid board, pressed by a sphere or a flat punch (a skin)",
            },
        ),
        Key("mechanics.outer_radius", q, "the dome's outer radius", "m", R, POSITIVE, LENGTH),
        Key("mechanics.thickness", q, "the dome's wall or the layer's (or skin's) thickness", "m", R, POSITIVE, LENGTH),
        Key(
            "mechanics.size",
            "quantities",
            "the skin's sides [along x, along y], centred on the origin",
            "m",
            R,
            POSITIVE,
            LENGTH,
            length=2,
        ),
        Key("mechanics.contact_area", q, "the layer's loaded area", "m^2", R, POSITIVE, AREA),
        Key(
            "mechanics.fidelity",
            "choice",
            "the mechanics model's level",
            default=D("reissner for a dome, hooke for a layer"),
            choices={
                "reissner": "dome: Reissner's thin-shell closed form",
                "axisymmetric": "dome: the finite-strain axisymmetric model",
                "hooke": "layer: Hooke's law over the contact area",
                "bonded": "layer: Hooke's law corrected for a bonded, nearly incompressible layer",
            },
        ),
        Key(
            "mechanics.mesh",
            "integers",
            "the axisymmetric dome's elements [through the wall, along the meridian]",
            default=[2, 16],
            length=2,
        ),
        Key(
            "mechanics.base",
            "choice",
            "how the dome's rim is held",
            default="bonded",
            choices={"bonded": "glued to the base", "sliding": "free to slide on the base"},
        ),
        Key(
            "mechanics.material",
            "choice",
            "the elastomer's constitutive law",
            default=D("required for a dome; 'linear' for a skin"),
            choices={
                "mooney_rivlin": "Mooney-Rivlin (c10, c01; a dome's)",
                "neo_hookean": "neo-Hookean (shear_modulus, bulk_modulus; a skin's: the press at finite strain)",
                "linear": "linear elastic (a dome's: youngs_modulus, poisson_ratio; a skin's: shear_modulus, "
                "poisson_ratio)",
            },
        ),
        Key("mechanics.c10", q, "Mooney-Rivlin constant C10", "Pa", R, POSITIVE, MODULUS),
        Key("mechanics.c01", q, "Mooney-Rivlin constant C01", "Pa", R, NONNEGATIVE, MODULUS),
        Key("mechanics.shear_modulus", q, "shear modulus mu (neo-Hookean, skin)", "Pa", R, POSITIVE, MODULUS),
        Key("mechanics.bulk_modulus", q, "neo-Hookean bulk modulus K", "Pa", R, POSITIVE, MODULUS),
        Key("mechanics.youngs_modulus", q, "linear Young's modulus E", "Pa", R, POSITIVE, MODULUS),
        Key(
            "mechanics.poisson_ratio",
            q,
            "Poisson's ratio nu (linear: below 0.5; skin: 0.5 exact)",
            "1",
            R,
            (-1.0, False, 0.5, True),
        ),
        Key(
            "mechanics.spring",
            q,
            "the ball's torsion spring: restoring force per radian of tilt",
            "N/rad",
            R,
            POSITIVE,
            (1e-9, 1e3),
        ),
        # [sensor]
        Key(
            "sensor.model",
            "choice",
            "the kind of magnetic sensor",
            choices={
                "hall3d": "3-axis Hall chips",
                "spin_valve": "spin-valve chips, one sensitive axis each",
                "gmr": "GMR bridges read differentially",
            },
        ),
        Key(
            "sensor.preset",
            "choice",
            "the sensor part",
            choices={n: m for n, (m, _) in _SENSOR_PRESETS.items()},
            presets={n: f for n, (_, f) in _SENSOR_PRESETS.items()},
        ),
        Key(
            "sensor.grid",
            "integers",
            "a grid of sensors, [rows, columns], centred on the axis",
            default=[1, 1],
            length=2,
        ),
        Key(
            "sensor.pitch", q, "the grid's spacing", "m", D("required with a grid; 0 for a film's"), NONNEGATIVE, LENGTH
        ),
        Key(
            "sensor.depth",
            q,
            "how far the grid (a skin's chips: their sensing points) lies below the sensor plane (a skin's bottom face)",
            "m",
            D("0 for a grid; required for a skin"),
            plausible=LENGTH,
        ),
        Key(
            "sensor.chips",
            "plane points",
            "a skin's chips, each one's position [x, y] (or sensor.grid and sensor.pitch)",
            "m",
            None,
            plausible=LENGTH,
        ),
        Key(
            "sensor.map_grid",
            "integers",
            "a skin's outputs: contact positions [along x, along y] over the chips' bounding box or sensor.map_size",
            default=[5, 5],
            length=2,
        ),
        Key(
            "sensor.map_size",
            "quantities",
            "the area [along x, along y] of a skin's outputs' map, centred on the skin's centre (absent: the chips' "
            "bounding box)",
            "m",
            None,
            POSITIVE,
            LENGTH,
            length=2,
        ),
        Key(
            "sensor.positions",
            "points",
            "each sensor's position [x, y, z] (absent: one sensor at the origin)",
            "m",
            None,
            plausible=LENGTH,
        ),
        Key("sensor.orientation", "choice", "how the chips are turned", default="aligned", choices=_POSE),
        Key("sensor.amplification", q, "the voltage gain after the spin valve or bridge", "1", 1.0, POSITIVE),
        Key("sensor.offset", q, "the GMR's offset along x from the pole's axis", "m", R, plausible=LENGTH),
        Key("sensor.height", q, "the GMR's height above the magnet plate", "m", R, NONNEGATIVE, LENGTH),
        # [indenter]: what presses a skin
        Key(
            "indenter.radius",
            q,
            "the radius of the sphere or flat punch that presses the skin",
            "m",
            R,
            POSITIVE,
            LENGTH,
        ),
        Key(
            "indenter.shape",
            "choice",
            "what presses the skin",
            default="sphere",
            choices={
                "sphere": "a rigid sphere: Hertz's contact patch, its radius growing with the force",
                "flat": "a rigid flat punch: Boussinesq's pressure on a patch of the punch's radius",
            },
        ),
        # [geometry]
        Key(
            "geometry.gap",
            q,
            "the rest distance from the magnet's face (or the ball's bottom) to the sensor plane (or plate)",
            "m",
            R,
            POSITIVE,
            LENGTH,
        ),
        # [load]
        Key("load.points", "integer", "the number of load points of the sweep", default=11),
        Key(
            "load.normal",
            "quantities",
            "the normal force [start, stop], ramped linearly",
            "N",
            None,
            plausible=FORCE,
            length=2,
        ),
        Key(
            "load.shear_x", "quantities", "the shear force along x [start, stop]", "N", None, plausible=FORCE, length=2
        ),
        Key(
            "load.shear_y", "quantities", "the shear force along y [start, stop]", "N", None, plausible=FORCE, length=2
        ),
        Key(
            "load.contact_x", "quantities", "the contact point's x [start, stop]", "m", None, plausible=LENGTH, length=2
        ),
        Key(
            "load.contact_y", "quantities", "the contact point's y [start, stop]", "m", None, plausible=LENGTH, length=2
        ),
        Key(
            "load.duration",
            q,
            "the sweep's duration",
            "s",
            D("one second per point (a quasi-static sweep)"),
            plausible=TIME,
        ),
        # [inductors]
        Key("inductors.positions", "points", "each chip inductor's position [x, y, z]", "m", R, plausible=LENGTH),
        Key("inductors.area", q, "the mean area of one turn", "m^2", R, POSITIVE, AREA),
        Key("inductors.turns", q, "the number of turns", "1", R, POSITIVE),
        Key("inductors.amplification", q, "the voltage gain of the EMF", "1", 1.0, POSITIVE),
        Key(
            "inductors.noise",
            q,
            "the standard deviation of the noise on each EMF reading",
            "V",
            0.0,
            NONNEGATIVE,
            VOLTAGE,
        ),
        Key("inductors.window", "integer", "the window of samples an event is counted over", default=20),
        # [pole]
        Key("pole.ball_radius", q, "the ball's radius", "m", R, POSITIVE, LENGTH),
        Key("pole.diameter", q, "the soft rod's diameter", "m", R, POSITIVE, LENGTH),
        Key(
            "pole.length", q, "the rod's length from the ball's bottom", "m", D("the ball's diameter"), POSITIVE, LENGTH
        ),
        Key(
            "pole.fidelity",
            "choice",
            "the pole's magnetic model",
            default="reduced",
            choices={
                "reduced": "a charge model with a demagnetizing factor",
                "moments": "the rod in cells, its magnetisation solved self-consistently",
            },
        ),
        Key(
            "pole.demagnetizing_factor", q, "the rod's demagnetizing factor (reduced)", "1", R, (0.0, False, 1.0, True)
        ),
        Key("pole.permeability", q, "the rod's relative permeability (moments)", "1", 1000.0, POSITIVE),
        Key(
            "pole.saturation",
            q,
            "the rod's saturation polarisation (moments; absent: linear)",
            "T",
            None,
            POSITIVE,
            FIELD,
        ),
        Key("pole.cells", "integer", "the rod's cells along its length (moments)", default=16),
        # [[soft]]
        Key(
            "soft.shape",
            "choice",
            "the soft part's shape",
            choices={
                "cuboid": "size = [x, y, z]",
                "cylinder": "size = [diameter, height]",
                "sphere": "size = diameter",
            },
        ),
        Key(
            "soft.size",
            "quantities",
            "the part's size (see shape); one quantity for a sphere",
            "m",
            R,
            POSITIVE,
            LENGTH,
        ),
        Key("soft.permeability", q, "the part's relative permeability", "1", R, POSITIVE),
        Key("soft.saturation", q, "the part's saturation polarisation (absent: linear)", "T", None, POSITIVE, FIELD),
        Key("soft.cells", "integer", "cells along the part's longest side", default=8),
        Key(
            "soft.position",
            "quantities",
            "the part's centre (x, y, z), scene frame",
            "m",
            R,
            plausible=LENGTH,
            length=3,
        ),
        Key(
            "soft.rotation",
            "quantities",
            "the part's rotation angles (x, y, z)",
            "rad",
            [0.0, 0.0, 0.0],
            plausible=ANGLE,
            length=3,
        ),
        Key("soft.moves", "bool", "whether the part moves with the magnet", default=False),
        # [design.*]: * is a scene parameter (dotted spec key) or an output's name
        Key("design.name", "text", "the design's name, shown above its report", default=D("the spec file's name")),
        Key("design.variables.*.lower", q, "the parameter's lowest value", "the parameter's unit"),
        Key("design.variables.*.upper", q, "the parameter's highest value", "the parameter's unit"),
        Key(
            "design.variables.*.start",
            q,
            "where the solve starts, only for a parameter the scene does not state (a start that differs "
            "from the scene's stated value is refused: the variable starts at that value)",
            "the parameter's unit",
            D("the scene's value"),
        ),
        Key(
            "design.variables.*.scale",
            q,
            "the solver's unit step of the parameter",
            "the parameter's unit",
            D("upper - lower"),
        ),
        Key("design.targets.*", "quantity or table", "an output held equal to this value", "the output's unit", None),
        Key("design.targets.*.value", q, "the target value", "the output's unit"),
        Key(
            "design.targets.*.scale",
            q,
            "the size a miss is judged by",
            "the output's unit",
            D("|value|; needed for a target of 0"),
        ),
        Key(
            "design.targets.*.tolerance",
            q,
            'the allowed miss of a tolerance analysis\'s samples ("%" of the value)',
            "the output's unit",
            None,
        ),
        Key("design.limits.*.lower", q, "the output's lowest allowed value", "the output's unit", None),
        Key("design.limits.*.upper", q, "the output's highest allowed value", "the output's unit", None),
        Key(
            "design.limits.*.scale",
            q,
            "the size a violation is judged by",
            "the output's unit",
            D("the bound's magnitude"),
        ),
        Key("design.objective.maximize", "output", "the output to maximise", default=None),
        Key("design.objective.minimize", "output", "the output to minimise", default=None),
        Key("design.report.*", "unit", "a further output to show, in this unit", default=None),
        Key(
            "design.grids",
            "grids",
            "a skin's candidate sensor.grid values: magdesign solve solves the design at each, fewest chips "
            "first, and reports the first that succeeds",
            default=None,
        ),
        Key(
            "design.tolerances.distribution",
            "choice",
            "the distribution of every tolerance",
            default="normal",
            choices={"normal": "sizes are standard deviations", "uniform": "sizes are half-widths"},
        ),
        Key(
            "design.tolerances.*",
            "quantity or table",
            'a scene parameter\'s tolerance ("%" of its value, or a quantity in its unit)',
            "the parameter's unit",
            None,
        ),
        Key("design.tolerances.*.value", q, "the tolerance's size", "the parameter's unit"),
        Key(
            "design.tolerances.*.distribution",
            "choice",
            "this tolerance's own distribution",
            default=D("design.tolerances.distribution"),
            choices={"normal": "a standard deviation", "uniform": "a half-width"},
        ),
        Key(
            "design.tolerances.placement",
            "quantities",
            "each sensor's placement tolerance (one quantity or x, y, z)",
            "m",
            None,
            NONNEGATIVE,
            LENGTH,
            length=3,
        ),
        Key(
            "design.tolerances.tilt",
            "quantities",
            "each chip's tilt tolerance (one quantity or alpha, beta, gamma)",
            "rad",
            None,
            NONNEGATIVE,
            ANGLE,
            length=3,
        ),
        Key(
            "design.tolerances.temperature",
            q,
            "the magnet's temperature tolerance",
            "K",
            None,
            NONNEGATIVE,
            (0.0, 500.0),
        ),
    ]


KEYS: dict[str, Key] = {key.name: key for key in _keys()}

# The tables in the order the reference shows them: the scene's, then the design's.
TABLES = tuple(dict.fromkeys(key.table for key in KEYS.values()))
