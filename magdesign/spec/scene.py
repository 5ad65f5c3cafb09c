"""Scenes from parsed TOML specs (units as strings; see the files in examples/).

Tables: [scene] (effects and their options), [magnet], [mechanics], [sensor],
[geometry], [load], [inductors] (the GMR-inductor sensor), [pole] (the magnetic-suspension
sensor), [indenter] (what presses a skin). [design] is ignored. The [magnet] table's
``shape`` picks the scene type: "cylinder" (the dome-Hall, spin-valve matrix and
GMR-inductor sensors, :class:`MagnetScene`), "film" (the film-Hall sensor,
:class:`FilmScene`), "plate" (the magnetic-suspension sensor, :class:`PoleScene`), "skin"
(a magnetised elastomer layer over a chip array, :class:`SkinScene`); docs/references.md
names the paper behind each.
"""

import dataclasses
import math

import equinox as eqx
import jax
import numpy as np

from magdesign._tracing import on_device, strongly_typed
from magdesign.fields.cylinder import FIDELITIES as CYLINDER_FIDELITIES
from magdesign.fields.soft import SIZE_LENGTHS, size_keywords, soft_body
from magdesign.mechanics import LinearElastic, MooneyRivlin, NeoHookean, time_constant_from_pole
from magdesign.mechanics.dome import BASES as DOME_BASES
from magdesign.mechanics.dome import DEFAULT_MESH
from magdesign.mechanics.dome import FIDELITIES as DOME_FIDELITIES
from magdesign.mechanics.layer import FIDELITIES as LAYER_FIDELITIES
from magdesign.mechanics.viscoelastic import DOME_HALL_POLE, DOME_HALL_SAMPLE_RATE
from magdesign.scene import effects as fx
from magdesign.scene.film_scene import FilmScene
from magdesign.scene.loads import loads_from_spec
from magdesign.scene.magnet_scene import Inductors, MagnetScene, SpinValveReadout
from magdesign.scene.mechanics import Dome, Layer
from magdesign.scene.pole_scene import PoleScene
from magdesign.scene.pose import Magnet, SoftPart, grid_positions, rotation
from magdesign.scene.skin_scene import SkinScene
from magdesign.scene.solids import Solid, check_apart, solid
from magdesign.spec.checks import fields
from magdesign.spec.keys import KEYS
from magdesign.spec.sizes import check_fits
from magdesign.spec.table import Table, check_tables
from magdesign.units import SpecError, echo, uT

# The scene's tables (all of the key table's but [design]) and the sensor parts by model.
TABLES = tuple(dict.fromkeys(key.table.split(".")[0] for key in KEYS.values() if key.table.split(".")[0] != "design"))
_PRESETS = KEYS["sensor.preset"].presets
HALL_PRESETS = {name: _PRESETS[name] for name in ("AK8963", "MLX90393")}
VALVE_PRESETS = {name: _PRESETS[name] for name in ("INESC", "PANASONIC")}
# The spin-valve matrix's read-out ADC (the spin-valve paper, Sections 3.5 and 4.1-4.2): 24-bit over 2.048 V full scale, 20-25 uV peak-to-peak noise,
# i.e. a standard deviation of about 22.5 uV / 6.6 (peak-to-peak of a Gaussian ~ 6.6 sigma).
ADC_FULL_SCALE = 2.048
ADC_BITS = 24
ADC_NOISE = 22.5e-6 / 6.6
EARTH_FIELD = 50.0 * uT
NDFEB_DRIFT = -0.12e-2  # 1/K


def _material(table):
    name = table.choice("material", ("mooney_rivlin", "neo_hookean", "linear"))
    if name == "mooney_rivlin":
        return MooneyRivlin(c10=on_device(table.quantity("c10", "Pa")), c01=on_device(table.quantity("c01", "Pa")))
    if name == "neo_hookean":
        return NeoHookean(
            mu=on_device(table.quantity("shear_modulus", "Pa")),
            bulk=on_device(table.quantity("bulk_modulus", "Pa")),
        )
    youngs, poisson = table.quantity("youngs_modulus", "Pa"), table.quantity("poisson_ratio", "1")
    if poisson >= 0.5:
        raise SpecError(
            f"{table.name}.poisson_ratio: {poisson:g} makes a linear material incompressible (an infinite bulk "
            "modulus, no volume change under pressure); expected a value below 0.5, e.g. 0.49 (a skin's bonded "
            "layer takes 0.5 exactly)"
        )
    return LinearElastic(E=on_device(youngs), nu=on_device(poisson))


def check_wall(thickness, outer_radius, key="mechanics.thickness"):
    """SpecError naming ``key`` unless a dome's wall (m) is thinner than its outer radius (m)."""
    if not thickness < outer_radius:
        raise SpecError(
            f"{key}: a {thickness * 1e3:g} mm wall does not fit in a dome of outer radius "
            f"{outer_radius * 1e3:g} mm; expected a wall thinner than the radius"
        )


# A magnet read back from a solved design held on its part's top (the guard embed >= 0, met
# to the solver's tolerance) touches it to this relative tolerance.
CONTACT_RTOL = 1e-9


def check_carried(gap, height, mechanics, key="geometry.gap"):
    """SpecError naming ``key`` (geometry.gap, or magnet.offset where it moves the magnet up
    or down) unless the magnet (near face ``gap`` (m) above the sensor plane, ``height`` (m)
    tall) touches the part that carries it (to :data:`CONTACT_RTOL`): on or in a layer
    (0 <= gap <= its thickness: not below the board the layer lies on), or at a dome's apex
    (its near face at or below the outer apex, its far face at or above the inner apex)."""
    # the guards' embed and reach, from a numpy copy of the mechanics (no program to compile)
    host = jax.tree.map(np.asarray, mechanics)
    top, bottom = float(host.top()), float(host.bottom())
    if isinstance(mechanics, Layer):
        if gap < -top * CONTACT_RTOL:
            raise SpecError(
                f"{key}: a magnet whose face is {gap * 1e3:g} mm from the sensor plane lies below it, in the board "
                "that the layer lies on; expected the magnet on or in the layer (its face 0 mm or more above the "
                "chips)"
            )
        if gap > top * (1.0 + CONTACT_RTOL):
            raise SpecError(
                f"{key}: a magnet whose face is {gap * 1e3:g} mm above the chips floats above the "
                f"{top * 1e3:g} mm layer that carries it (mechanics.thickness); expected a gap at most the "
                "layer's thickness (the magnet on or in the layer)"
            )
    if isinstance(mechanics, Dome):
        if not (bottom * (1.0 - CONTACT_RTOL) <= gap + height and gap <= top * (1.0 + CONTACT_RTOL)):
            raise SpecError(
                f"{key}: a {height * 1e3:g} mm magnet whose face is {gap * 1e3:g} mm above the chips "
                f"misses the apex of the dome that carries it (its wall spans {bottom * 1e3:g} to "
                f"{top * 1e3:g} mm); expected a gap from {(bottom - height) * 1e3:g} to {top * 1e3:g} mm"
            )


def check_magnet_fits(radius, outer_radius, key="magnet.radius"):
    """SpecError naming ``key`` unless a magnet of ``radius`` (m) is narrower than the dome
    of ``outer_radius`` (m) whose apex carries it."""
    if not radius < outer_radius:
        raise SpecError(
            f"{key}: a magnet of radius {radius * 1e3:g} mm is wider than the dome that carries it "
            f"(mechanics.outer_radius = {outer_radius * 1e3:g} mm); expected a radius below the dome's"
        )


def _cylinder_solid(key, centre, radius, height, angles=None) -> Solid:
    """A cylinder magnet as a :class:`Solid`; ``angles`` (rad) its rotation, None: axis along z."""
    radius, height = float(radius), float(height)
    turn = None if angles is None else np.asarray(rotation(angles)).T
    return solid(key, "cylinder", np.asarray(centre, float), [radius, radius, height / 2], turn)


def _soft_solid(key, part) -> Solid:
    """A [[soft]] part at rest as a :class:`Solid` (its size: diameters, heights, sides)."""
    size = [float(v) / 2 for v in part.size]
    half = {"sphere": size * 3, "cylinder": [size[0], size[0], size[-1]], "cuboid": size}[part.shape]
    return solid(key, part.shape, np.asarray(part.centre, float), half, np.asarray(rotation(part.angles)).T)


def _counts(table, key, default, what):
    """The list of positive integers ``key`` of ``table`` (``default`` when absent) as a
    tuple; SpecError naming the key and ``what`` the integers count ("[along x, along y]")."""
    value = table._get(key, default, "integers")
    if not (
        isinstance(value, list)
        and len(value) == len(default)
        and all(isinstance(n, int) and not isinstance(n, bool) and n >= 1 for n in value)
    ):
        raise SpecError(
            f"{table.name}.{key}: expected {what} ({len(default)} positive integers, e.g. {default}), got {echo(value)}"
        )
    return tuple(value)


def _mesh(table):
    """The dome's mesh [elements through the wall, along the meridian] as a tuple."""
    return _counts(table, "mesh", list(DEFAULT_MESH), "[elements through the wall, along the meridian]")


def _mechanics(spec, fidelity, models=("dome", "layer")):
    table = Table(spec, "mechanics")
    model = table.choice("model", models)
    if model == "dome":
        levels = DOME_FIDELITIES
        outer_radius, thickness = table.quantity("outer_radius", "m"), table.quantity("thickness", "m")
        check_wall(thickness, outer_radius)
        mechanics = Dome(
            outer_radius=on_device(outer_radius),
            thickness=on_device(thickness),
            material=_material(table),
            fidelity=table.choice("fidelity", levels, default="reissner"),
            base=table.choice("base", DOME_BASES, default="bonded"),
            mesh=_mesh(table),
        )
    else:
        levels = LAYER_FIDELITIES
        mechanics = Layer(
            thickness=on_device(table.quantity("thickness", "m")),
            contact_area=on_device(table.quantity("contact_area", "m^2")),
            material=_material(table),
            fidelity=table.choice("fidelity", levels, default="hooke"),
        )
    table.done()
    if fidelity is not None:
        if fidelity not in levels:
            raise SpecError(f"fidelity: expected one of {', '.join(map(repr, levels))} for a {model}, got {fidelity!r}")
        mechanics = dataclasses.replace(mechanics, fidelity=fidelity)
    if mechanics.fidelity == "axisymmetric" and isinstance(mechanics.material, LinearElastic):
        raise SpecError(
            "mechanics.material: the axisymmetric dome needs a finite-strain law (mooney_rivlin or "
            "neo_hookean); 'linear' holds for the reissner level only"
        )
    return mechanics


def _sensor_layout(table):
    """Positions (S, 3) (m) and nominal chip angles (S, 3) (rad) from [sensor]."""
    if table.has("grid"):
        grid = grid_positions(_grid(table), table.quantity("pitch", "m"))
        positions = np.asarray(grid) - [0.0, 0.0, table.quantity("depth", "m", default=0.0)]
    elif table.has("positions"):
        positions = np.array(table.points("positions", default=None))
    else:
        positions = np.zeros((1, 3))
    orientation = table.choice("orientation", ("aligned", "radial"), default="aligned")
    angles = np.zeros_like(positions)
    if orientation == "radial":
        # sensitive axis a along the outward radius: Rz(gamma) maps (cos phi, sin phi) to a
        angles[:, 2] = -np.arctan2(positions[:, 1], positions[:, 0])
    return on_device(positions), on_device(angles)


def _grid(table):
    value = table._get("grid", [1, 1])
    if not (isinstance(value, list) and len(value) == 2 and all(isinstance(v, int) and v > 0 for v in value)):
        raise SpecError(f"sensor.grid: expected [rows, columns] (positive integers), got {echo(value)}")
    return tuple(value)


# Reading-stage option keys of [scene], read only for listed effects.
_EFFECT_KEYS = tuple(key for key in fields("scene") if key != "effects")


def _effects(spec, reading_unit, *, saturation, lsb, noise):
    """The [scene] table's effects with their options (defaults from the transducer)."""
    table = Table(spec, "scene", required=False)
    names = table.strings("effects", default=[])
    for name in names:
        if name not in fx.EFFECT_NAMES:
            raise SpecError(f"scene.effects: unknown effect {name!r}; expected any of: {', '.join(fx.EFFECT_NAMES)}")
        if names.count(name) > 1:
            raise SpecError(f"scene.effects: {name!r} listed twice")

    def scalar(key, unit, default):
        return on_device(table.quantity(key, unit, default=default))

    def vector(key, unit, default):
        return on_device(table.quantities(key, unit, length=len(default), default=default))

    build = {
        "temperature_drift": lambda: fx.TemperatureDrift(
            coefficient=scalar("temperature_coefficient", "1/K", NDFEB_DRIFT),
            temperature_change=scalar("temperature_change", "K", 10.0),
        ),
        "placement": lambda: fx.Placement(offsets=vector("placement", "m", [200e-6, 0.0, 0.0])),
        "chip_tilt": lambda: fx.ChipTilt(angles=vector("tilt", "rad", [10.0 * np.pi / 180, 0.0, 0.0])),
        "viscoelastic_lag": lambda: fx.ViscoelasticLag(
            time_constant=scalar(
                "lag_time_constant", "s", float(time_constant_from_pole(DOME_HALL_POLE, DOME_HALL_SAMPLE_RATE))
            )
        ),
        "area_averaging": lambda: fx.AreaAveraging(
            size=vector("area", "m", [200e-6, 95e-6]), points=table.integer("quadrature", default=3)
        ),
        "background": lambda: fx.Background(field_=vector("background", "T", [0.0, 0.0, EARTH_FIELD])),
        "saturation": lambda: fx.Saturation(limit=scalar("saturation_limit", reading_unit, saturation)),
        "noise": lambda: fx.Noise(sigma=scalar("noise", reading_unit, noise)),
        "quantisation": lambda: fx.Quantisation(lsb=scalar("lsb", reading_unit, lsb)),
    }
    chosen = fx.in_order([build[name]() for name in names])
    table._known.extend(_EFFECT_KEYS)
    table.done()
    return chosen


def _hall(table):
    preset = table.choice("preset", tuple(HALL_PRESETS))
    return HALL_PRESETS[preset]()


def _hall_effects(spec, hall):
    # per axis (x, y, z may differ: the MLX90393's z range and LSB are its x, y ones x 1.6)
    return _effects(spec, "T", saturation=hall.full_scale, lsb=hall.lsb, noise=hall.lsb)


def _optional_vector(table, key, unit):
    """A (3,) array from a list of 3 quantities, or None when the key is absent."""
    value = table.quantities(key, unit, length=3, default=None)
    return None if value is None else on_device(value)


def _posed_tables(raw, key, moves):
    """Each table of a ``[[key]]`` array: (its name, Table, centre (3,) (m, scene frame),
    angles (3,) (rad), moves); ``moves`` the default of its ``moves`` flag. The Table is
    checked for unknown keys when the caller has read it."""
    if not isinstance(raw, list) or not all(isinstance(item, dict) for item in raw):
        raise SpecError(f"{key}: expected [[{key}]] tables, got {echo(raw)}")
    for index, item in enumerate(raw):
        name = f"{key}[{index}]"
        table = Table({name: item}, name)
        flag = table.flag("moves", moves)
        centre = on_device(table.quantities("position", "m", length=3))
        angles = on_device(table.quantities("rotation", "rad", length=3, default=[0.0, 0.0, 0.0]))
        yield name, table, centre, angles, flag
        table.done()


def _extra_magnets(magnet):
    """[[magnet.extra]]: further cylinders, each at its centre (scene frame) and rotation."""
    return tuple(
        Magnet(
            radius=on_device(table.quantity("radius", "m")),
            height=on_device(table.quantity("height", "m")),
            polarization=on_device(table.quantities("polarization", "T", length=3)),
            centre=centre,
            angles=angles,
            moves=moves,
        )
        for _, table, centre, angles, moves in _posed_tables(magnet._get("extra", []), "magnet.extra", True)
    )


SOFT_CELLS = 8


def _soft_grid(key, shape, size, cells, permeability):
    """The cell grid of a soft body, or a SpecError naming ``key`` (a size that cannot fit:
    the dense interaction matrix of its n cells, (3 n)^2 values; ``cells`` along the longest
    side, the others in proportion)."""
    sides = {"cuboid": size, "cylinder": [size[0], size[0], size[-1]], "sphere": [size[0]] * 3}[shape]
    count = math.prod(max(1, round(int(cells) * side / max(sides))) for side in sides)
    check_fits(f"{key} = {cells}", (3.0 * count) ** 2, what="the cells' interaction matrix")
    try:
        return soft_body(shape, **size_keywords(shape, size), cells=cells, permeability=permeability).grid
    except ValueError as error:
        raise SpecError(f"{key}: {error}") from None


def _saturation(table, name, permeability):
    """A soft body's optional saturation polarisation J_s (T), or None (linear)."""
    saturation = table.quantity("saturation", "T", default=None)
    if saturation is not None and permeability <= 1.0:
        raise SpecError(f"{name}.saturation: a saturating body needs {name}.permeability > 1, got {permeability:g}")
    return None if saturation is None else on_device(saturation)


def _soft_parts(spec):
    """[[soft]]: soft-magnetic parts (method of moments), each at its centre (scene frame)
    and rotation, fixed unless ``moves = true``, linear unless it gives a ``saturation``."""
    parts = []
    for name, table, centre, angles, moves in _posed_tables(spec.get("soft", []), "soft", False):
        shape = table.choice("shape", tuple(SIZE_LENGTHS))
        count = SIZE_LENGTHS[shape]
        size = table.quantities("size", "m", length=count) if count > 1 else [table.quantity("size", "m")]
        permeability = table.quantity("permeability", "1")
        saturation = _saturation(table, name, permeability)
        grid = _soft_grid(f"{name}.cells", shape, size, table.integer("cells", default=SOFT_CELLS), permeability)
        parts.append(
            SoftPart(
                size=tuple(on_device(v) for v in size),
                permeability=on_device(permeability),
                centre=tuple(centre),
                angles=angles,
                shape=shape,
                grid=grid,
                moves=moves,
                saturation=saturation,
            )
        )
    return tuple(parts)


def _direction(magnet):
    """A table's direction (a magnet's) as a unit vector (3,), or None when absent."""
    direction = _optional_vector(magnet, "direction", "1")
    if direction is None:
        return None
    norm = float(np.linalg.norm(direction))
    if norm == 0.0:
        raise SpecError(f"{magnet.name}.direction: expected a nonzero vector [x, y, z], got zeros")
    return on_device(np.asarray(direction) / norm)


def _cylinder_scene(spec, fidelity):
    magnet = Table(spec, "magnet")
    magnet.choice("shape", ("cylinder",))
    radius, height = magnet.quantity("radius", "m"), magnet.quantity("height", "m")
    remanence = magnet.quantity("remanence", "T")
    field_fidelity = magnet.choice("fidelity", CYLINDER_FIDELITIES, default="exact")
    direction = _direction(magnet)
    offset = _optional_vector(magnet, "offset", "m")
    magnet_angles = _optional_vector(magnet, "rotation", "rad")
    extra = _extra_magnets(magnet)
    magnet.done()
    parts = _soft_parts(spec)
    posed = [
        key
        for key, value in (("direction", direction), ("offset", offset), ("rotation", magnet_angles))
        if value is not None
    ]
    if field_fidelity == "axis" and (posed or extra):
        key = posed[0] if posed else "extra"
        raise SpecError(f"magnet.{key}: fidelity 'axis' holds for one axial magnet on the sensors' axis; use 'exact'")
    if field_fidelity == "axis" and parts:
        raise SpecError(
            "magnet.fidelity: 'axis' is the magnet's field on its axis, and the [[soft]] parts read it "
            "off the axis; use 'exact'"
        )
    mechanics = _mechanics(spec, fidelity)
    sensor = Table(spec, "sensor")
    sensor_key = next((f"sensor.{key}" for key in ("positions", "grid") if sensor.has(key)), "sensor")
    model = sensor.choice("model", ("hall3d", "spin_valve", "gmr"))
    if model == "hall3d":
        transducer = _hall(sensor)
        positions, angles = _sensor_layout(sensor)
        sensor.done()
        effects = _hall_effects(spec, transducer)
    else:
        if model == "spin_valve":
            preset = sensor.choice("preset", tuple(VALVE_PRESETS))
            valve = VALVE_PRESETS[preset]()
        else:
            valve = _PRESETS[sensor.choice("preset", ("AA003-02",))]()
        amplification = sensor.quantity("amplification", "1", default=1.0)
        differential = model == "gmr"
        transducer = SpinValveReadout(valve, on_device(amplification), differential)
        positions, angles = _sensor_layout(sensor)
        sensor.done()
        effects = _effects(
            spec, "V", saturation=ADC_FULL_SCALE, lsb=ADC_FULL_SCALE / 2 ** (ADC_BITS - 1), noise=ADC_NOISE
        )
    if field_fidelity == "axis" and np.any(np.asarray(positions)[:, :2] != 0.0):
        raise SpecError("magnet.fidelity: 'axis' needs every sensor on the magnet's axis (x = y = 0)")
    off_axis = [effect.name for effect in effects if effect.name in ("placement", "area_averaging")]
    if field_fidelity == "axis" and off_axis:
        raise SpecError(
            f"magnet.fidelity: 'axis' holds on the magnet's axis only, and the {off_axis[0]} effect "
            "reads the field off it; use 'exact'"
        )
    geometry = Table(spec, "geometry")
    gap = geometry.quantity("gap", "m")
    geometry.done()
    lift = 0.0 if offset is None else float(offset[2])
    check_carried(gap + lift, height, mechanics, key="magnet.offset" if lift else "geometry.gap")
    if isinstance(mechanics, Dome):
        check_magnet_fits(radius, float(mechanics.outer_radius))
    magnet_centre = np.array([0.0, 0.0, gap + height / 2]) + (0.0 if offset is None else np.asarray(offset))
    solids = [_cylinder_solid("magnet", magnet_centre, radius, height, magnet_angles)]
    solids += [
        _cylinder_solid(f"magnet.extra[{i}]", m.centre, m.radius, m.height, m.angles) for i, m in enumerate(extra)
    ]
    solids += [_soft_solid(f"soft[{i}]", part) for i, part in enumerate(parts)]
    sensors = [(sensor_key, positions)]
    inductors = None
    if "inductors" in spec:
        table = Table(spec, "inductors")
        inductors = Inductors(
            positions=on_device(table.points("positions")),
            area=on_device(table.quantity("area", "m^2")),
            turns=on_device(table.quantity("turns", "1")),
            amplification=on_device(table.quantity("amplification", "1", default=1.0)),
            noise=on_device(table.quantity("noise", "V", default=0.0)),
            window=table.integer("window", default=20, minimum=2),
        )
        table.done()
        sensors.append(("inductors.positions", inductors.positions))
    check_apart(sensors, solids)
    return MagnetScene(
        radius=on_device(radius),
        height=on_device(height),
        remanence=on_device(remanence),
        gap=on_device(gap),
        mechanics=mechanics,
        sensor_positions=positions,
        sensor_angles=angles,
        transducer=transducer,
        effects=effects,
        inductors=inductors,
        fidelity=field_fidelity,
        direction=direction,
        offset=offset,
        angles=magnet_angles,
        extra=extra,
        soft=parts,
    )


def _film_scene(spec, fidelity):
    magnet = Table(spec, "magnet")
    magnet.choice("shape", ("film",))
    period, thickness = magnet.quantity("period", "m"), magnet.quantity("thickness", "m")
    magnetization = magnet.quantity("magnetization", "T")
    periods = magnet.integer("periods", default=None)  # None: an infinite film
    magnet.done()
    layer = _mechanics(spec, fidelity, models=("layer",))
    sensor = Table(spec, "sensor")
    sensor.choice("model", ("hall3d",))
    hall = _hall(sensor)
    grid = _grid(sensor)
    pitch = sensor.quantity("pitch", "m", default=0.0)
    sensor.done()
    return FilmScene(
        period=on_device(period),
        film_thickness=on_device(thickness),
        magnetization=on_device(magnetization),
        layer=layer,
        pitch=on_device(pitch),
        hall=hall,
        effects=_hall_effects(spec, hall),
        grid=grid,
        periods=periods,
    )


# The moments level's defaults: Ni-Fe (the secondary models of Sajat's 2008 thesis) and
# the rod's cells along its length (the error/cost rows of `magdesign accuracy`).
NIFE_PERMEABILITY = 1000.0
POLE_CELLS = 16


def _pole_scene(spec, fidelity):
    if fidelity is not None:
        raise SpecError(f"fidelity: the pole scene has one (reduced) mechanics model, got {fidelity!r}")
    magnet = Table(spec, "magnet")
    magnet.choice("shape", ("plate",))
    radius, height = magnet.quantity("radius", "m"), magnet.quantity("height", "m")
    remanence = magnet.quantity("remanence", "T")
    magnet.done()
    pole = Table(spec, "pole")
    ball_radius = pole.quantity("ball_radius", "m")
    diameter = pole.quantity("diameter", "m")
    length = pole.quantity("length", "m", default=2.0 * ball_radius)  # the rod through the whole ball
    if length > 2.0 * ball_radius:
        raise SpecError(
            f"pole.length: a {length * 1e3:g} mm rod does not fit in a ball of radius "
            f"{ball_radius * 1e3:g} mm; expected at most its diameter"
        )
    if not diameter < 2.0 * ball_radius:
        raise SpecError(
            f"pole.diameter: a rod of diameter {diameter * 1e3:g} mm does not fit in a ball of radius "
            f"{ball_radius * 1e3:g} mm (pole.ball_radius); expected a diameter below the ball's"
        )
    level = pole.choice("fidelity", ("reduced", "moments"), default="reduced")
    demag = permeability = rod_cells = saturation = None
    if level == "reduced":
        demag = on_device(pole.quantity("demagnetizing_factor", "1"))
    else:
        permeability = pole.quantity("permeability", "1", default=NIFE_PERMEABILITY)
        saturation = _saturation(pole, "pole", permeability)
        cells = pole.integer("cells", default=POLE_CELLS)
        rod_cells = _soft_grid("pole.cells", "cylinder", [diameter, length], cells, permeability)
        permeability = on_device(permeability)
    pole.done()
    mechanics = Table(spec, "mechanics")
    mechanics.choice("model", ("tilt",))
    spring = mechanics.quantity("spring", "N/rad")
    mechanics.done()
    geometry = Table(spec, "geometry")
    gap = geometry.quantity("gap", "m")
    geometry.done()
    sensor = Table(spec, "sensor")
    sensor.choice("model", ("gmr",))
    valve = _PRESETS[sensor.choice("preset", ("PANASONIC",))]()
    offset = sensor.quantity("offset", "m")
    sensor_height = sensor.quantity("height", "m")
    sensor.done()
    check_apart(
        [("sensor.height", [offset, 0.0, sensor_height])],
        [
            _cylinder_solid("magnet", [0.0, 0.0, -height / 2], radius, height),
            solid("pole.ball_radius", "sphere", [0.0, 0.0, gap + ball_radius], [ball_radius] * 3),
        ],
    )
    return PoleScene(
        plate_radius=on_device(radius),
        plate_thickness=on_device(height),
        remanence=on_device(remanence),
        gap=on_device(gap),
        ball_radius=on_device(ball_radius),
        pole_diameter=on_device(diameter),
        pole_length=on_device(length),
        demagnetizing_factor=demag,
        permeability=permeability,
        saturation=saturation,
        fidelity=level,
        rod_cells=rod_cells,
        spring=on_device(spring),
        sensor_offset=on_device(offset),
        sensor_height=on_device(sensor_height),
        transducer=SpinValveReadout(valve, on_device(1.0), True),
        effects=_effects(
            spec, "V", saturation=ADC_FULL_SCALE, lsb=ADC_FULL_SCALE / 2 ** (ADC_BITS - 1), noise=ADC_NOISE
        ),
    )


def check_carried_loads(scene, loads):
    """SpecError naming the [load] key of a shear force that ``scene``'s mechanics does not
    carry: a dome's model takes the normal load only (a shear would be dropped, the magnet
    left in place), the pole's spring tilts the ball about one axis (shear_x only)."""
    shear = np.abs(np.asarray(loads.shear)).max(axis=0)
    dome = isinstance(getattr(scene, "mechanics", None), Dome)
    carried = (0,) if isinstance(scene, PoleScene) else () if dome else (0, 1)
    for axis, name in enumerate(("shear_x", "shear_y")):
        if shear[axis] > 0.0 and axis not in carried:
            model = "the dome model carries normal load only" if not carried else "the model carries shear_x only"
            raise SpecError(f"load.{name}: {model}; a {shear[axis]:g} N shear would be dropped without a word")


def check_field_samples(scene, points):
    """SpecError (a size that cannot fit in memory) or SizeWarning (a long run) for the field
    samples a simulation of ``scene`` over ``points`` load points takes: points x sensors x
    quadrature points per chip x 3 components (:func:`magdesign.spec.sizes.check_fits`)."""
    if isinstance(scene, FilmScene):
        sensors = int(np.prod(scene.grid))
    elif isinstance(scene, SkinScene):
        sensors = len(scene.chips)
    else:
        sensors = int(np.shape(getattr(scene, "sensor_positions", np.zeros((1, 3))))[0])
    quadrature = max((effect.points for effect in scene.effects if effect.name == "area_averaging"), default=1)
    check_fits(
        f"load.points = {points}, {sensors} sensors, scene.quadrature = {quadrature}",
        3.0 * points * sensors * quadrature**2,
        what="the field samples",
    )


def _skin_scene(spec, fidelity):
    from magdesign.spec.skin import skin_scene  # spec.skin builds on this module's tables

    return skin_scene(spec, fidelity)


_SCENES = {"cylinder": _cylinder_scene, "film": _film_scene, "plate": _pole_scene, "skin": _skin_scene}


def scene_from_spec(spec: dict, *, fidelity: str | None = None):
    """Build a scene from a parsed TOML spec (all tables but [design], which is ignored).

    ``fidelity``, when given, overrides the spec's mechanics fidelity. Raises
    :class:`~magdesign.units.SpecError` (one line, naming the key) on bad input.
    """
    check_tables(spec, TABLES)
    loads = loads_from_spec(spec)  # a bad [load] table is a bad spec, whatever runs next
    points = loads.normal.shape[0]
    shape = Table(spec, "magnet").choice("shape", tuple(_SCENES))
    if "soft" in spec and shape not in ("cylinder", "skin"):
        raise SpecError(
            "soft: [[soft]] parts are magnetised by cylinder magnets (magnet.shape = 'cylinder') or a skin, "
            f"not a {shape}"
        )
    if "indenter" in spec and shape != "skin":
        raise SpecError(f"indenter: an [indenter] presses a skin (magnet.shape = 'skin'), not a {shape}")
    scene = _SCENES[shape](spec, fidelity)
    if isinstance(scene, SkinScene):
        from magdesign.spec.skin import check_skin_loads

        check_skin_loads(scene, loads)
    check_carried_loads(scene, loads)
    check_field_samples(scene, points)
    # a time derivative (the inductors' EMF) or a lag needs a time series
    needs_series = [
        name
        for name, wanted in (
            ("the inductors' EMF", getattr(scene, "inductors", None) is not None),
            ("the viscoelastic_lag effect", any(e.name == "viscoelastic_lag" for e in scene.effects)),
        )
        if wanted
    ]
    if needs_series and points < 2:
        raise SpecError(f"load.points: {needs_series[0]} needs a time series of at least 2 load points, got {points}")
    # strongly typed leaves, as with_parameters makes them: a jitted function of the scene
    # then compiles once for the spec's scene and for any copy with new parameter values
    return jax.tree.map(lambda leaf: strongly_typed(leaf) if eqx.is_inexact_array(leaf) else leaf, scene)
