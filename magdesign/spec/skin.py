"""The spec of a magnetic skin (magnet.shape = "skin"): its tables read into a
:class:`~magdesign.scene.skin_scene.SkinScene`, and the checks of its chips and loads.
Called by :func:`magdesign.spec.scene.scene_from_spec`, whose table readers it shares."""

import math
import warnings

import jax.numpy as jnp
import numpy as np

from magdesign._tracing import on_device
from magdesign.fields.layer_field import finer
from magdesign.scene.pose import grid_positions
from magdesign.scene.skin_scene import (
    CONTACT_FORCE_FLOOR,
    FIELD_MODELS,
    INDENTERS,
    LAYER_MATERIALS,
    NODES_PER_PERIOD,
    SkinMagnets,
    SkinScene,
    default_resolution,
)
from magdesign.scene.solids import check_apart, solid
from magdesign.spec.checks import PlausibilityWarning
from magdesign.spec.scene import (
    CONTACT_RTOL,
    _counts,
    _direction,
    _grid,
    _hall,
    _hall_effects,
    _soft_parts,
    _soft_solid,
)
from magdesign.spec.sizes import check_fits
from magdesign.spec.table import Table
from magdesign.units import SpecError, echo

# The Hertz contact radius over the layer's thickness up to which a skin's half-space contact
# patch holds to about 3 % (magdesign.scene.skin_scene): beyond it a spec warns.
SKIN_CONTACT_RATIO = 0.5
# The strain under the contact (SkinScene.contact_strain) above which a spec warns: the linear
# layer is a neo-Hookean (or Mooney-Rivlin) elastomer's first order in the strain, and their
# stresses part by about the strain itself. In uniaxial compression to the stretch l = 1 - e
# the neo-Hookean's nominal stress mu (l - l^-2) is (l^-2 - l) / (3 e) - 1 above Hooke's
# 3 mu e: 11.5 % at e = 0.1, beyond the few per cent of the model's other reaches.
SKIN_STRAIN_LIMIT = 0.1
# A sphere's contact strain is a / R, the pressed surface's slope at the patch's edge; Hertz's
# stresses (Johnson 1985, eq. 3.45, nu = 0.5) put the largest strain inside lower: on the axis,
# 0.55 a deep, sigma_r - sigma_z reaches 0.533 p0 with p0 = 8 mu a / (pi R), a uniaxial strain
# (sigma_r - sigma_z) / (3 mu) = 0.45 a / R. The warning's stress excess is taken there.
HERTZ_PEAK_STRAIN = 0.45
# The Cramer-Rao bound of a contact's (x, y, Fn, F_x, F_y) needs 5 readings or more: two 3-axis chips.
SKIN_MIN_CHIPS = 2


def check_on_skin(keys, points, size):
    """SpecError naming ``keys[0]`` (x) or ``keys[1]`` (y) unless every point (x, y) (m),
    shape (n, 2), lies on a skin of sides ``size`` (m) centred on the origin."""
    points, half = np.asarray(points, dtype=float).reshape(-1, 2), np.asarray(size, dtype=float) / 2
    for axis, key in enumerate(keys):
        worst = float(np.max(np.abs(points[:, axis]), initial=0.0))
        if worst > half[axis] * (1.0 + CONTACT_RTOL):
            raise SpecError(
                f"{key}: a {'xy'[axis]} of {worst * 1e3:g} mm from the centre lies off the "
                f"{size[0] * 1e3:g} x {size[1] * 1e3:g} mm skin (mechanics.size); expected at most "
                f"{half[axis] * 1e3:g} mm"
            )


def check_skin_loads(scene, loads):
    """SpecError naming the [load] key unless ``loads`` press ``scene`` (a skin) on its top
    face: contacts on the skin, normal forces of 0 or more, the largest above 0 (the outputs
    are taken at it); a PlausibilityWarning where a contact or a point of the outputs' map
    lies within one thickness of the skin's side (the layer's mechanics is the unbounded
    layer's), and :func:`check_contact_patch`'s."""
    size = np.asarray(scene.size)
    check_on_skin(("load.contact_x", "load.contact_y"), loads.contact, size)
    normal = np.asarray(loads.normal)
    if np.any(normal < 0.0):
        raise SpecError(
            f"load.normal: {float(normal.min()):g} N would pull on the skin; an indenter only presses: expected "
            "forces of 0 N or more"
        )
    if not normal.max() > 0.0:
        raise SpecError(
            "load.normal: the skin's outputs are taken at the sweep's largest normal force, 0 N here, where a "
            "contact has no position to find; expected a press above 0 N"
        )
    thickness = float(scene.thickness)
    map_key = "sensor.map_grid" if scene.map_size is None else "sensor.map_size"
    for key, points in (("load.contact", loads.contact), (map_key, scene.map_points(xp=np))):
        margin = float(np.min(size / 2 - np.abs(np.asarray(points))))
        if margin < thickness:
            warnings.warn(
                f"{key}: a point lies {margin * 1e3:.3g} mm from the skin's side, within its {thickness * 1e3:g} mm "
                "thickness; the layer is modelled without sides (its displacement is the unbounded layer's), "
                "which its free side changes there",
                PlausibilityWarning,
                stacklevel=3,
            )
    check_contact_patch(scene, float(normal.max()))
    check_contact_strain(scene, loads)


def check_contact_patch(scene, force):
    """Warn (:class:`~magdesign.spec.checks.PlausibilityWarning`) where the skin's contact
    radius under ``force`` (N) exceeds SKIN_CONTACT_RATIO times its thickness: the sphere's
    Hertz radius (naming load.normal), or the flat punch's own (naming indenter.radius)."""
    radius, thickness = float(scene.contact_radius(force, xp=np)), float(scene.thickness)
    if radius <= SKIN_CONTACT_RATIO * thickness:
        return
    reach = f"the half-space contact patch holds to about {SKIN_CONTACT_RATIO:g}"
    if scene.indenter == "flat":
        message = (
            f"indenter.radius: the flat punch's {radius * 1e3:.3g} mm radius is {radius / thickness:.2g} times "
            f"the {thickness * 1e3:g} mm skin; {reach} (a smaller punch or a thicker skin)"
        )
    else:
        message = (
            f"load.normal: at {force:g} N the sphere's Hertz contact radius is {radius * 1e3:.3g} mm, "
            f"{radius / thickness:.2g} times the {thickness * 1e3:g} mm skin; {reach} (a smaller force, a "
            "smaller indenter.radius or a stiffer layer)"
        )
    warnings.warn(message, PlausibilityWarning, stacklevel=2)


def neo_hookean_excess(strain: float) -> float:
    """How far (-) a neo-Hookean elastomer's nominal stress in uniaxial compression by
    ``strain`` e (-, 0 < e < 1) lies above Hooke's of the same initial modulus:
    mu (l^-2 - l) / (3 mu e) - 1 at the stretch l = 1 - e (0.115 at e = 0.1)."""
    stretch = 1.0 - strain
    return (stretch**-2 - stretch) / (3.0 * strain) - 1.0


def check_contact_strain(scene, loads):
    """Warn (:class:`~magdesign.spec.checks.PlausibilityWarning`) where the largest strain
    in the layer under the contact exceeds SKIN_STRAIN_LIMIT at some point of ``loads`` (the
    sweep) with a press of CONTACT_FORCE_FLOOR or more: the linear layer's stresses are then
    off by about the strain itself. The strain is
    :meth:`~magdesign.scene.skin_scene.SkinScene.contact_strain`, the patch's travel over
    its radius, times HERTZ_PEAK_STRAIN for a sphere whose depth is the larger travel.
    Names load.normal (load.shear_x / shear_y where the shear's travel is the larger part),
    mechanics.shear_modulus and the indenter."""
    normals, shears = np.asarray(loads.normal, dtype=float), np.asarray(loads.shear, dtype=float)
    if scene.material == "neo_hookean":
        check_shear_strain(scene, normals, shears)
        return
    travels = scene.contact_strain(normals, shears, xp=np)
    nu = float(scene.poisson_ratio)
    # which travel dominates: the depth's 2 (1 - nu) Fn or the shear's (2 - nu) |F_t|
    sheared = (2.0 - nu) * np.hypot(shears[..., 0], shears[..., 1]) > 2.0 * (1.0 - nu) * normals
    hertz = (scene.indenter != "flat") & ~sheared
    insides = np.where(normals >= CONTACT_FORCE_FLOOR, np.where(hertz, HERTZ_PEAK_STRAIN, 1.0) * travels, 0.0)
    worst = int(np.argmax(insides))
    inside = float(insides[worst])
    if not inside > SKIN_STRAIN_LIMIT:
        return
    strain = float(travels[worst])
    normal, shear, sheared = float(normals[worst]), shears[worst], bool(sheared[worst])
    key = ("load.shear_x" if abs(shear[0]) >= abs(shear[1]) else "load.shear_y") if sheared else "load.normal"
    radius = float(scene.contact_radius(normal, xp=np))
    travel = f"the {'flat punch' if scene.indenter == 'flat' else 'sphere'}'s travel over its {radius * 1e3:.3g} mm "
    travel += "radius" if scene.indenter == "flat" else "Hertz contact radius"
    if scene.indenter != "flat" and not sheared:
        measure = f"{HERTZ_PEAK_STRAIN:g} x {travel}, a / R = {strain:.2g}: Hertz's stresses inside"
    else:
        measure = travel
    remedy = "a wider punch" if scene.indenter == "flat" else "a larger sphere"
    excess = f"{100 * neo_hookean_excess(min(inside, 0.5)):.0f} %"
    excess = excess if inside < 0.5 else f"over {excess}"
    warnings.warn(
        f"{key}: at {normal:g} N (shear ({shear[0]:g}, {shear[1]:g}) N) the largest strain under the contact is "
        f"{inside:.2g} ({measure}) on the {float(scene.shear_modulus) / 1e3:g} kPa layer (mechanics.shear_modulus): "
        f"above {SKIN_STRAIN_LIMIT:g}, where a neo-Hookean elastomer's stress departs from the linear layer's by "
        f"about the strain (in uniaxial compression by 11.5 % at {SKIN_STRAIN_LIMIT:g}, {excess} at {inside:.2g}), "
        f"so its displacements and the outputs may be off by as much; a smaller force, a stiffer layer or {remedy} "
        "(indenter.radius) lowers the strain (mechanics.thickness does not, while the patch is small against it)",
        PlausibilityWarning,
        stacklevel=2,  # at one place whoever builds the scene: the command says it once
    )


def check_shear_strain(scene, normals, shears):
    """A neo_hookean layer's :func:`check_contact_strain`: its press is finite-strain, its
    shear the linear layer's, superposed; warn where the shear's own strain under the
    contact (:meth:`~magdesign.scene.skin_scene.SkinScene.contact_strain` of the shear
    alone, on the press's patch) exceeds SKIN_STRAIN_LIMIT at a press of CONTACT_FORCE_FLOOR or more."""
    travels = scene.contact_strain(normals, shears, xp=np, press=False)
    strains = np.where(normals >= CONTACT_FORCE_FLOOR, travels, 0.0)
    worst = int(np.argmax(strains))
    if not strains[worst] > SKIN_STRAIN_LIMIT:
        return
    shear = shears[worst]
    key = "load.shear_x" if abs(shear[0]) >= abs(shear[1]) else "load.shear_y"
    warnings.warn(
        f"{key}: at {float(normals[worst]):g} N (shear ({shear[0]:g}, {shear[1]:g}) N) the shear's own strain under "
        f"the contact is {float(strains[worst]):.2g} (its travel over the contact radius): above "
        f"{SKIN_STRAIN_LIMIT:g}; the neo_hookean layer (mechanics.material) carries the press at finite strain but "
        "the shear as the linear layer does, superposed on it, so the shear's part of the displacement may be off "
        "by about that strain (a smaller shear, a stiffer layer or a larger sphere lowers it)",
        PlausibilityWarning,
        stacklevel=3,
    )


def _neo_hookean_layer(mechanics, shear_modulus):
    """(Poisson's ratio of the linear shear part, bulk modulus K (Pa)) of a neo_hookean
    layer's [mechanics] table: K read, nu = (3 K - 2 mu) / (2 (3 K + mu)) derived."""
    if mechanics.has("poisson_ratio"):
        raise SpecError(
            "mechanics.poisson_ratio: a neo_hookean layer (mechanics.material) takes bulk_modulus (Pa) instead; its "
            "Poisson's ratio (3 K - 2 mu) / (2 (3 K + mu)) follows from the two moduli"
        )
    bulk = mechanics.quantity("bulk_modulus", "Pa")
    if not bulk > 0.0:
        raise SpecError(f"mechanics.bulk_modulus: {bulk:g} Pa; expected a bulk modulus above 0 Pa")
    if not shear_modulus > 0.0:
        raise SpecError(f"mechanics.shear_modulus: {shear_modulus:g} Pa; expected a shear modulus above 0 Pa")
    return (3.0 * bulk - 2.0 * shear_modulus) / (2.0 * (3.0 * bulk + shear_modulus)), bulk


def _skin_chips(sensor):
    """(the skin's chips (S, 2) (m), None), or (a grid's unit offsets, its pitch (m): the
    parameter sensor.pitch, which a design varies), and the key that placed them."""
    if sensor.has("grid") == sensor.has("chips"):
        raise SpecError(
            "sensor.chips: expected the chips' positions [[x, y], ...] or sensor.grid with sensor.pitch "
            f"({'both were' if sensor.has('grid') else 'neither was'} given)"
        )
    if sensor.has("grid"):
        pitch = sensor.quantity("pitch", "m")
        if not pitch > 0.0:
            raise SpecError(
                f"sensor.pitch: a grid at {pitch * 1e3:g} mm pitch puts every chip at one place; expected a pitch "
                "above 0 mm"
            )
        return np.asarray(grid_positions(_grid(sensor), 1.0))[:, :2], pitch, "sensor.grid"
    chips = np.asarray(sensor.points("chips", default=None, plane=True), dtype=float).reshape(-1, 2)
    for i, j in zip(*np.triu_indices(len(chips), k=1)):
        if np.array_equal(chips[i], chips[j]):
            raise SpecError(
                f"sensor.chips: chips {i} and {j} both sit at {np.round(chips[i] * 1e3, 6).tolist()} mm; expected "
                "each chip at its own place (two chips at one place read the same field)"
            )
    return chips, None, "sensor.chips"


def _skin_magnets(magnet, direction, size, thickness):
    """[[magnet.magnets]]: an eFlesh-like skin's discrete magnets (SkinMagnets; None when
    absent), each inside the layer (else a SpecError naming its position), its direction
    its own, else magnet.direction, else through the thickness."""
    raw = magnet._get("magnets", [])
    if not isinstance(raw, list) or not all(isinstance(item, dict) for item in raw):
        raise SpecError(f"magnet.magnets: expected [[magnet.magnets]] tables, got {echo(raw)}")
    rows = []
    for index, item in enumerate(raw):
        table = Table({f"magnet.magnets[{index}]": item}, f"magnet.magnets[{index}]")
        centre, sides = (np.asarray(table.quantities(key, "m", length=3)) for key in ("position", "size"))
        own = _direction(table)
        table.done()
        room = np.array([size[0] / 2, size[1] / 2, thickness / 2])
        if np.any(np.abs(centre - [0.0, 0.0, thickness / 2]) + sides / 2 > room * (1.0 + CONTACT_RTOL)):
            raise SpecError(
                f"{table.name}.position: the magnet at {np.round(centre * 1e3, 6).tolist()} mm reaches out of the "
                f"{size[0] * 1e3:g} x {size[1] * 1e3:g} x {thickness * 1e3:g} mm layer (0 <= z <= mechanics.thickness)"
            )
        rows.append([centre, sides, next(v for v in (own, direction, (0.0, 0.0, 1.0)) if v is not None)])
    if not rows:
        return None
    centres, sizes, directions = (jnp.asarray(np.array(column, dtype=float)) for column in zip(*rows))
    return SkinMagnets(centres=centres, sizes=sizes, directions=directions)


def _skin_period(magnet, direction):
    """(magnet.period (m) or None, the direction): a patterned skin's polarization turns in the
    x-z plane, from magnet.direction at x = 0, by default (0, 0, -1) (the film's pattern, strong
    side down); a SpecError naming magnet.direction for a direction out of that plane."""
    if not magnet.has("period"):
        return None, direction
    period = magnet.quantity("period", "m")  # the key table refuses 0 m or less, naming it
    if direction is None:
        return period, (0.0, 0.0, -1.0)
    if abs(direction[1]) > 0.0:
        raise SpecError(
            f"magnet.direction: {np.round(np.asarray(direction), 6).tolist()} has a y component, but the "
            "pattern of magnet.period turns the polarization about y (in the x-z plane); expected the "
            "polarization at x = 0 in that plane, e.g. [0, 0, -1] (the film's pattern) or no magnet.direction"
        )
    return period, direction


def _check_pattern_nodes(key, counts, size, period):
    """SpecError naming magnet.<key> where its nodes (or cells) along x sample the pattern of
    ``period`` (m) fewer than twice a period (the pattern aliases: at two a period every node
    may fall on a zero of J_z); a PlausibilityWarning below NODES_PER_PERIOD a period, the
    default resolution's. ``counts`` None: the default resolution, which resolves the period."""
    if counts is None:
        return
    per_period = counts[0] * period / size[0]
    if per_period <= 2.0:
        raise SpecError(
            f"magnet.{key}: {counts[0]} along x over the {size[0] * 1e3:g} mm layer is {per_period:.3g} per "
            f"{period * 1e3:g} mm period (magnet.period), too few to carry the pattern; expected more than "
            f"{math.floor(2.0 * size[0] / period)} along x"
        )
    if per_period < NODES_PER_PERIOD:
        warnings.warn(
            f"magnet.{key}: {counts[0]} along x is {per_period:.3g} per {period * 1e3:g} mm period "
            f"(magnet.period); the default puts {NODES_PER_PERIOD} in a period, and the field's error "
            "grows as the spacing squared",
            PlausibilityWarning,
            stacklevel=2,  # at one place whoever builds the scene: the command says it once
        )


def _skin_soft_parts(spec, size, thickness, chips, depth):
    """[[soft]] parts near a skin: fixed (the load moves the layer only), apart from the
    layer and from the chips' sensing points; SpecError naming the part otherwise."""
    parts = _soft_parts(spec)
    for i, part in enumerate(parts):
        if part.moves:
            raise SpecError(
                f"soft[{i}].moves: a skin's load moves its layer, not the parts near it; expected moves = false"
            )
    layer = solid("the skin's layer", "cuboid", [0.0, 0.0, thickness / 2], [size[0] / 2, size[1] / 2, thickness / 2])
    points = np.concatenate([chips, np.full((len(chips), 1), -depth)], axis=-1)
    check_apart([("sensor.chips", points)], [layer] + [_soft_solid(f"soft[{i}]", p) for i, p in enumerate(parts)])
    return parts


def skin_scene(spec, fidelity):
    """The :class:`~magdesign.scene.skin_scene.SkinScene` of a spec (magnet.shape = "skin"),
    or a SpecError naming the key."""
    if fidelity is not None:
        raise SpecError(
            f"fidelity: the skin has one mechanics model (a bonded layer, mechanics.material), got {fidelity!r}"
        )
    for name in ("geometry", "inductors", "pole"):
        if name in spec:
            raise SpecError(f"[{name}]: a skin reads no [{name}] table (its layer lies on the board at z = 0)")
    magnet = Table(spec, "magnet")
    magnet.choice("shape", ("skin",))
    polarization = magnet.quantity("polarization", "T")
    direction = _direction(magnet)
    mechanics = Table(spec, "mechanics")
    mechanics.choice("model", ("bonded_layer",))
    thickness = mechanics.quantity("thickness", "m")
    size = mechanics.quantities("size", "m", length=2)
    shear_modulus = mechanics.quantity("shear_modulus", "Pa")
    material = mechanics.choice("material", LAYER_MATERIALS, default="linear")
    bulk_modulus = None
    if material == "neo_hookean":
        poisson_ratio, bulk_modulus = _neo_hookean_layer(mechanics, shear_modulus)
    else:
        if mechanics.has("bulk_modulus"):
            raise SpecError(
                'mechanics.bulk_modulus: a linear layer (mechanics.material = "linear", the default) takes '
                'poisson_ratio; set mechanics.material = "neo_hookean" for shear_modulus and bulk_modulus'
            )
        poisson_ratio = mechanics.quantity("poisson_ratio", "1")
    mechanics.done()
    magnets = _skin_magnets(magnet, direction, size, thickness)
    period, direction = _skin_period(magnet, direction)
    for key in ("cells", "field", "resolution", "period"):
        if magnets is not None and magnet.has(key):
            raise SpecError(
                f"magnet.{key}: a skin with [[magnet.magnets]] has an unmagnetised layer (its magnets' own fields)"
            )
    field = magnet.choice("field", FIELD_MODELS, default="linear")
    cells = _counts(magnet, "cells", [16, 16, 8], "[along x, along y, through the thickness]")
    if field == "linear" and magnet.has("cells"):
        raise SpecError(
            'magnet.cells: the linear field (magnet.field = "linear", the default) has no cells; set '
            'magnet.field = "cells" for the rigid cells, or magnet.resolution for the linear field\'s nodes'
        )
    given = magnet.has("resolution")
    resolution = _counts(magnet, "resolution", [40, 40, 6], "[along x, along y, Gauss nodes through the thickness]")
    if given and field != "linear":
        raise SpecError('magnet.resolution: only the linear field (magnet.field = "linear") has nodes')
    resolution = resolution if given else None
    if period is not None:
        _check_pattern_nodes(*(("cells", cells) if field == "cells" else ("resolution", resolution)), size, period)
    magnet.done()
    indenter = Table(spec, "indenter")
    radius = indenter.quantity("radius", "m")
    indenter_shape = indenter.choice("shape", tuple(INDENTERS), default="sphere")
    indenter.done()
    if material == "neo_hookean" and indenter_shape != "sphere":
        raise SpecError(
            'indenter.shape: the neo_hookean layer (mechanics.material) is pressed by a sphere only; got "flat" '
            '(the flat punch presses the linear layer: mechanics.material = "linear")'
        )
    if material == "neo_hookean" and (magnets is None and field == "linear"):
        raise SpecError(
            'mechanics.material: the neo_hookean layer\'s press moves the rigid cells (magnet.field = "cells") or '
            'the discrete magnets ([[magnet.magnets]]); the linear field (magnet.field = "linear", the default) '
            "takes the linear layer's band-limited displacement, which the finite-strain press does not give"
        )
    sensor = Table(spec, "sensor")
    sensor.choice("model", ("hall3d",))
    hall = _hall(sensor)
    offsets, pitch, chips_key = _skin_chips(sensor)
    chips = offsets if pitch is None else offsets * pitch
    depth = sensor.quantity("depth", "m")
    map_grid = _counts(sensor, "map_grid", [5, 5], "[along x, along y]")
    map_size = sensor.quantities("map_size", "m", length=2, default=None)
    sensor.done()
    if chips.shape[0] < SKIN_MIN_CHIPS:
        raise SpecError(
            f"{chips_key}: {chips.shape[0]} chip(s) read 3 numbers each, too few for a contact's position and "
            f"3 forces (5 unknowns); expected at least {SKIN_MIN_CHIPS} chips"
        )
    check_on_skin((chips_key, chips_key), chips, size)
    if map_size is not None and np.any(np.asarray(map_size) > np.asarray(size) * (1.0 + CONTACT_RTOL)):
        raise SpecError(
            f"sensor.map_size: a {map_size[0] * 1e3:g} x {map_size[1] * 1e3:g} mm map centred on the skin reaches "
            f"off the {size[0] * 1e3:g} x {size[1] * 1e3:g} mm skin (mechanics.size); expected at most its sides"
        )
    if not depth > 0.0:
        raise SpecError(
            f"sensor.depth: chips {depth * 1e3:g} mm below the board's surface would sit in the skin; expected "
            "a depth above 0 mm (the chips' sensing points under the skin's bottom face)"
        )
    if magnets is None and field == "linear":
        resolution = resolution or default_resolution(size, depth, period)
        label, sources = f"magnet.resolution = {list(resolution)}", math.prod(finer(resolution))
    elif magnets is None:
        label, sources = f"magnet.cells = {list(cells)}", math.prod(cells)
    else:
        label, sources = "magnet.magnets", magnets.centres.shape[0]
    check_fits(
        f"{label}, {chips.shape[0]} chips",
        15.0 * sources * chips.shape[0],
        what="the layer's field at the chips and its derivatives",
    )
    soft = _skin_soft_parts(spec, size, thickness, chips, depth)
    effects = _hall_effects(spec, hall)
    # the outputs' noise: the listed noise effect's, else one LSB per axis (scene.noise's default)
    noise = next((effect.sigma for effect in effects if effect.name == "noise"), hall.lsb)
    # the scene's leaves put on the device without a program (on_device): a spec's build runs no JAX
    return SkinScene(
        thickness=on_device(thickness),
        size=on_device(size),
        polarization=on_device(polarization),
        shear_modulus=on_device(shear_modulus),
        poisson_ratio=on_device(poisson_ratio),
        sphere_radius=on_device(radius),
        chips=offsets,  # numpy: split into the scene's pairs without a program
        pitch=None if pitch is None else on_device(pitch),
        depth=on_device(depth),
        noise=on_device(np.broadcast_to(np.asarray(noise, dtype=float), (3,))),
        hall=hall,
        effects=effects,
        direction=(0.0, 0.0, 1.0) if direction is None else tuple(float(v) for v in np.asarray(direction)),
        cells=cells,
        map_grid=map_grid,
        map_size=None if map_size is None else tuple(map_size),
        magnets=magnets,
        field=field,
        resolution=resolution,
        indenter=indenter_shape,
        soft=soft,
        period=None if period is None else on_device(period),
        material=material,
        bulk_modulus=None if bulk_modulus is None else on_device(bulk_modulus),
    )
