"""A magnetic skin: a magnetised elastomer layer bonded over an array of 3-axis chips (the
ReSkin / AnySkin class: Bhirangi et al., "ReSkin: versatile, replaceable, lasting tactile
skins", 2021), pressed by a rigid sphere or a flat punch.

Scene frame: the board's surface is z = 0; the layer (thickness h, sides L_x x L_y,
centred on the origin) fills 0 <= z <= h, bonded to the board; the chips' sensing points
sit ``depth`` below the surface, at the given (x, y). The layer carries a uniform
polarization J = J0 d (T, d a static unit vector: through the thickness or in-plane), or,
with a ``period`` T, the sinusoidal film's Halbach pattern along x, J(x) = J0 R_y(k x) d,
k = 2 pi / T: d turned about y by k x (:func:`magdesign.fields.layer_field.pattern`; with
d = (0, 0, -1), J0 (-sin kx, 0, -cos kx), the film's pattern of
:class:`~magdesign.scene.FilmScene`, strong side down towards the chips, x = 0 the layer's
centre and a peak of its z component). The layer carries the pattern as its sides cut it,
uniform along y. The
chips' positions are each a pair of scalars (x, y), so that a design can move one chip
along one axis (``sensor.chips[i][k]``);
a grid's chips are its unit offsets times ``pitch`` (``sensor.pitch``), so that a design can
space the whole grid.

A load point is a contact at (x, y) on the top surface with a normal force Fn (pressing)
and a shear force (F_x, F_y). The sphere of radius R presses a patch of Hertz's radius
a = (3 Fn R / (4 E*))^(1/3) with Hertz's pressure and a shear traction of the same shape
(:mod:`magdesign.mechanics.skin_layer`; the half-space contact radius holds for a / h up to
about 0.3 and is 3 % off at 0.5); below the force CONTACT_FORCE_FLOOR the patch keeps that
force's radius (the displacement, proportional to the forces on a given patch, is then nil
anyway). A rigid flat punch (``indenter="flat"``, the spec's ``indenter.shape``) of radius
R presses a patch of its own radius, whatever the force, with Boussinesq's pressure
Fn / (2 pi R^2 sqrt(1 - r^2 / R^2)) and a shear traction of that shape (the same reach in
R / h as Hertz's patch).

The layer's displacement field (linear elasticity: displacements small against h) moves its
particles and turns them with the material's rotation curl(u) / 2. With ``material``
"neo_hookean" (static; ``bulk_modulus`` K given, ``poisson_ratio`` the one derived from mu and
K) the sphere's normal press moves them as the finite-strain layer computes it
(:func:`magdesign.mechanics.finite_layer.press_field`: its displacement and rotation at the
cells' centres or the magnets', NaN where its Newton solve did not converge), and the shear
traction's part is the linear layer's, superposed (first order in the shear: docs/skins.md);
only the sphere, and only the cells and the discrete magnets, which take point values (the
linear field takes the linear layer's band-limited displacement). Two field models
(``field``, static):

- ``"linear"`` (the default): the field to first order in the displacement, the block's
  exact field plus the integral of the moved and turned particles' dipoles over the layer
  (:func:`magdesign.fields.layer_field.layer_field`), on ``resolution`` (n_x, n_y, Gauss
  nodes; static: by :func:`default_resolution`, 2 nodes per ``depth`` across the layer, and
  NODES_PER_PERIOD per period of a pattern, and GAUSS_NODES through it, from the concrete
  values at construction). A patterned layer's undeformed field is a sum of slabs across x
  (:func:`~magdesign.fields.layer_field.pattern_field`, its error stated there). The
  displacement and rotation at the nodes come from the layer's Fourier sums
  (:func:`magdesign.mechanics.skin_layer.layer_displacement_grid`) cut at the node grid's own
  wavenumbers (:func:`band_limited_grid`, the reason in the field's module). Its
  discretisation error is :meth:`SkinScene.field_error`, the change to the finer resolution
  (:func:`~magdesign.fields.layer_field.finer`); at the default it is about 0.1-0.2 % of
  the largest change of the field at the chips under a press.
- ``"cells"``: the layer cut into ``cells`` rigid cuboid cells
  (:mod:`magdesign.fields.cells`), each moved by the displacement at its centre and turned by
  the rotation there (:func:`magdesign.fields.cells.carried_cells`), each cell carrying the
  pattern's J at its centre where the layer is patterned, the displacement and rotation from
  the Fourier sums on the cell grid (about 1e-4 of the peak displacement from the Hankel
  quadrature's values) on the lattice ``spectral`` (static:
  :func:`~magdesign.mechanics.skin_layer.spectral_grid` of the size and thickness the scene is
  built with, unless given). A cell as thick as the layer moves its bonded bottom face with
  its centre, and a cell wider than the contact patch spreads the press over its width: the
  field's change converges as the cells thin (as n_z^-2) and shrink below the patch. Under
  the example's centred 0.2 N press (a 2 mm layer, the centre chip 1 mm below) the centre
  chip's Bz changes by -0.8, -108 and -85 uT at 4 x 4 x 2, 16 x 16 x 8 and 20 x 20 x 16
  cells, where the linear field gives -7.09 uT (docs/skins.md); the outputs converge worse.

An eFlesh-like skin (Pattabiraman et al., "eFlesh: highly customizable magnetic touch
sensing using cut-cell microstructures", 2025: a printed soft lattice carrying small magnets
over magnetometers) carries discrete magnets instead (``magnets``, :class:`SkinMagnets`):
cuboids inside the layer, the lattice taken as the effective elastic layer (its homogenised
moduli). The layer itself is then unmagnetised; each magnet carries the polarization J0 along
its own direction, moves rigidly with the layer's displacement at its centre and turns with
the material's rotation there (:func:`magdesign.fields.cells.moved_cells`, the displacement
from the layer's Hankel quadrature, :func:`~magdesign.mechanics.skin_layer.layer_displacement`).
A magnet stiffer than the lattice moves as a rigid body, as modelled; that it stiffens the
lattice around it is left out (the effective layer's moduli are the lattice's alone).

The mechanics' "displacement" of this scene is the load itself: each load point's
(x, y, Fn, F_x, F_y) (m, m, N, N, N), which the scene's motion effects (a lag) act on.

Outputs (:meth:`SkinScene.outputs`), from the Jacobian of every chip's reading with respect
to (x, y, Fn, F_x, F_y) on a map of contact positions (a ``map_grid`` over the chips'
bounding box or the stated ``map_size``, :meth:`SkinScene.map_points`) at the sweep's
largest normal force and its shear, with the chips' noise (``noise``, T per axis):

    localisation_worst / localisation_median   the Cramer-Rao bound of the contact position,
                           sqrt(var x + var y) (m), worst and median over the map
    force_resolution_normal / force_resolution_shear   the bound's deviation of Fn and of
                           the shear magnitude's worst axis (N), worst over the map
    force_resolution_shear_x / force_resolution_shear_y   the bound's deviation of F_x and
                           of F_y (N), each worst over the map (force_resolution_shear is
                           the larger of the two)
    crosstalk              the largest |correlation| between a normal and a shear force
                           estimate over the map (-)
    background_force_error the normal-force error (N) that a uniform field along the worst
                           axis causes, through the least-squares fit of all readings, worst
                           over the map; the field's size is the listed background effect's
                           |B| (the field the spec states the chips sit in), else
                           BACKGROUND_REFERENCE (the Earth's, 50 uT)
                           (:meth:`SkinScene.background_reference`)
    saturation_ratio       the largest |reading| over every chip, axis and load point of the
                           sweep over the chips' range (-)
    saturation_force       the largest normal force (N) that presses no chip axis out of its
                           range, worst (smallest) over the map and the sweep's contacts
                           (below)
    mechanics_converged    1 if the mechanics carries every load point of the sweep, else 0
                           (-): always the linear layer; the neo_hookean layer where its
                           press's Newton solve converged at each Fn (the outputs' map
                           presses at the sweep's largest Fn, so it covers them too) and
                           at saturation_force's (a NaN there, a press on its search that
                           the layer did not carry, gives 0)

``saturation_force`` presses along the sweep's largest load: a normal force F with the shear
F (F_x, F_y) / Fn of the sweep's point of largest Fn, at each contact position of the map and
of the sweep. Each chip axis's reading over its range (``chip_range``), c_i(F), is read by
:meth:`SkinScene.readings_at` (the background and the other static effects included), and the
output is the first F > 0 at which some |c_i(F)| reaches 1: the press's largest force before a
chip saturates, even where a larger force would bring a reading back in range. At rest the
readings hold the layer's own field (and the background), which may already lie near the
range, and a press may lower the largest |c_i| before another axis saturates: the largest
|reading| is not monotone in F, so the output follows each axis on its own. At a fixed contact
radius the displacement, and so each c_i, is linear in F: c_i(F) = c_i(0) + F k_i, whose first
crossing is F_i = (1 - sign(k_i) c_i(0)) / |k_i|. The flat punch's radius is fixed, so one
secant through rest and the sweep's largest force is exact; the sphere's Hertz patch grows as
F^(1/3), so k_i is taken again through the last answer (the secant through rest and it) until
the answer moves by less than SATURATION_RTOL (at most SATURATION_STEPS times). This assumes
that no c_i leaves and re-enters the range before the answer (each is linear in F at a given
patch; the patch's growth bends it slowly). A last Newton step on the binding axis,
F - (c_i(F) - (+-1)) / c_i'(F) with F and c_i'(F) held fixed, gives the answer its derivative
by the implicit function theorem (dF = -dc_i / c_i'), so that a design can hold it as a limit.
An axis at or past its range at rest gives 0 (``saturation_ratio`` says by how much); a press
that saturates no axis up to SATURATION_FORCE_CAP gives the cap (its derivative 0).
"""

import math
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from magdesign._numerics import safe_div, safe_norm
from magdesign._tracing import on_device
from magdesign._validation import _concrete
from magdesign.fields.cells import carried_cells, cells_field, layer_cells, moved_cells
from magdesign.fields.layer_field import finer, gauss_levels, layer_field, pattern
from magdesign.mechanics.finite_layer import press_converged, press_field
from magdesign.mechanics.materials import NeoHookean
from magdesign.mechanics.skin_layer import (
    ElasticLayer,
    SpectralGrid,
    SurfaceLoad,
    layer_displacement,
    layer_displacement_grid,
    spectral_grid,
)
from magdesign.scene.core import MECHANICS_CONVERGED, STATIC_WITHOUT, AbstractScene, chain
from magdesign.scene.effects import AbstractEffect, Background, judged_saturation
from magdesign.scene.loads import Loads
from magdesign.scene.pose import SoftPart, soft_parameter_paths, soft_parts_field
from magdesign.transducers import Hall3D, cramer_rao
from magdesign.units import uT

# Below this normal force (N) the contact patch keeps this force's Hertz radius (module docstring).
CONTACT_FORCE_FLOOR = 1e-3
# The largest force (N) saturation_force reports: a skin that no press up to it saturates
# reports it (a kilonewton: far past the loads a linear layer models).
SATURATION_FORCE_CAP = 1e3
# saturation_force's secant steps end when the force moves by less than this relative step,
# or after SATURATION_STEPS (module docstring).
SATURATION_RTOL = 1e-6
SATURATION_STEPS = 8
# A uniform field of the Earth's size (T), the reference of background_force_error where the
# scene lists no background.
BACKGROUND_REFERENCE = 50 * uT
# The unknowns of a load point and their units, the order of the Jacobian's columns.
LOAD_UNKNOWNS = ("x", "y", "normal", "shear_x", "shear_y")
# The magnetised layer's field models (module docstring).
FIELD_MODELS = ("linear", "cells")
# The layer's materials (module docstring).
LAYER_MATERIALS = ("linear", "neo_hookean")
# What presses the skin, and the load profile of each (module docstring).
INDENTERS = {"sphere": "hertz", "flat": "flat"}
# The linear model's default resolution: in-plane nodes at most 1 / NODES_PER_DEPTH of the
# chips' depth apart, and GAUSS_NODES heights through the thickness (module docstring).
NODES_PER_DEPTH = 2.0
GAUSS_NODES = 6
# A patterned layer's in-plane nodes along x: at least this many per period, so that the
# integrand's pattern (J(x') times the displacement's modes) is resolved as well.
NODES_PER_PERIOD = 8


def default_resolution(size, depth, period=None) -> tuple[int, int, int]:
    """The linear field's default (n_x, n_y, Gauss nodes) for a layer of sides ``size`` (m,
    (2,)) over chips ``depth`` (m) below it, patterned with ``period`` (m; None: uniform),
    from their concrete values (module docstring)."""
    patterned = period is not None
    sides, depth, period = _concrete(size), _concrete(depth), _concrete(period) if patterned else None
    if sides is None or depth is None or (patterned and period is None):
        raise ValueError("default_resolution needs the concrete size, depth and period (not traced values)")
    n = [max(2, math.ceil(NODES_PER_DEPTH * float(side) / float(depth))) for side in sides]
    if patterned:
        n[0] = max(n[0], math.ceil(NODES_PER_PERIOD * float(sides[0]) / float(period)))
    return (n[0], n[1], GAUSS_NODES)


def band_limited_grid(periods: tuple[int, int], levels: int) -> SpectralGrid:
    """The linear field's wavevector lattice: ``periods`` (P_x, P_y) cells, cut at the node
    grid's own wavenumbers on each of ``levels`` heights (:mod:`magdesign.fields.layer_field`)."""
    return SpectralGrid(periods=tuple(periods), refine=((1, 1),) * levels)


def linear_grid(size, thickness, resolution: tuple[int, int, int]) -> SpectralGrid:
    """The linear field's lattice for a layer of sides ``size`` (m, (2,)) and ``thickness``
    (m), concrete, at ``resolution`` (n_x, n_y, Gauss nodes): :func:`spectral_grid`'s periods
    (the layer and its padding) for the node grid, cut at its wavenumbers."""
    nx, ny, nodes = resolution
    plane = spectral_grid(size=size, thickness=thickness, cells=(nx, ny, 1))
    return band_limited_grid(plane.periods, nodes)


def first_crossings(rest: Float[Array, " k"], slope: Float[Array, " k"]) -> Float[Array, " k"]:
    """The force F > 0 (N) at which each range fraction rest + F slope (-, slope in 1/N)
    first reaches +1 or -1: (1 - sign(slope) rest) / |slope|; SATURATION_FORCE_CAP where the
    slope is 0 or the crossing lies beyond it, 0 where |rest| >= 1 (out of range at rest)."""
    crossing = safe_div(1.0 - jnp.sign(slope) * rest, jnp.abs(slope), at_zero=SATURATION_FORCE_CAP)
    return jnp.where(jnp.abs(rest) >= 1.0, 0.0, jnp.minimum(crossing, SATURATION_FORCE_CAP))


def _held(tree):
    """``tree`` with every array leaf's derivative stopped (the search's fixed point)."""
    return jax.tree.map(lambda leaf: jax.lax.stop_gradient(leaf) if eqx.is_array(leaf) else leaf, tree)


def _chip_pairs(chips) -> tuple[tuple[Float[Array, ""], Float[Array, ""]], ...]:
    """Chips' positions (S, 2) as S pairs of scalars (x, y): leaves a design sets one by one.
    Concrete positions are split in numpy and put on the device one by one (no program to
    compile, :func:`~magdesign._tracing.on_device`); traced ones by indexing."""
    concrete = _concrete(chips)
    rows = jnp.asarray(chips, dtype=float) if concrete is None else np.asarray(concrete, dtype=float)
    if rows.ndim != 2 or rows.shape[-1] != 2:
        raise ValueError(f"chips must be the chips' (x, y), shape (S, 2), got shape {rows.shape}")
    return tuple((on_device(row[0]), on_device(row[1])) for row in rows)


class SkinMagnets(eqx.Module):
    """Discrete magnets embedded in a skin's layer (an eFlesh-like skin, module docstring):
    M cuboids, each with its ``centres`` (x, y, z) at rest (m, scene frame, inside the layer),
    ``sizes`` (its sides, m) and ``directions`` (its polarization's unit vector), (M, 3) each.
    They carry the scene's ``polarization`` J0 (T)."""

    centres: Float[Array, "m 3"]
    sizes: Float[Array, "m 3"]
    directions: Float[Array, "m 3"]


class SkinScene(AbstractScene):
    """A magnetic skin over a chip array (module docstring); lengths (m), J0 (T), moduli (Pa).

    ``direction`` (static): the polarization's unit vector (at x = 0 where the layer is
    patterned); ``period``: None for a uniform layer, else the pattern's period T (m; module
    docstring); ``field`` (static): "linear" or
    "cells" (module docstring); ``resolution`` (static): the linear field's nodes (n_x, n_y,
    Gauss nodes), by default :func:`default_resolution`'s; ``cells`` (static): the layer's
    cells (n_x, n_y, n_z) of the "cells" field; ``map_grid`` (static): the outputs' contact
    positions (n_x, n_y), over the chips' bounding box or ``map_size`` (static, m, (L_x,
    L_y) centred on the origin); ``spectral`` (static): the field's wavevector lattice (the linear
    field's or the cells'), by default chosen from the concrete size and thickness at
    construction (module docstring). ``indenter`` (static): "sphere" or "flat" (a rigid
    flat punch), of radius ``sphere_radius`` (m). ``chips``: each chip's (x, y)
    (m), given as an (S, 2) array and kept as pairs of scalars (each a design parameter); in
    units of ``pitch`` (m) where a pitch is given (a grid's unit offsets): the chips then sit
    at ``chips * pitch`` (:meth:`chip_positions`). ``magnets``: discrete magnets in an
    unmagnetised layer (an eFlesh-like skin), or None for a magnetised layer.
    ``soft``: fixed soft-magnetic parts near the skin (nearby iron, ``[[soft]]``), magnetised
    by the skin's field under each load (:func:`~magdesign.scene.pose.soft_parts_field`).
    ``material`` (static): "linear" or "neo_hookean" (the press from the finite-strain layer,
    of ``shear_modulus`` and ``bulk_modulus`` (Pa); module docstring).
    """

    thickness: Float[Array, ""]
    size: Float[Array, "2"]
    polarization: Float[Array, ""]
    shear_modulus: Float[Array, ""]
    poisson_ratio: Float[Array, ""]
    sphere_radius: Float[Array, ""]
    chips: tuple[tuple[Float[Array, ""], Float[Array, ""]], ...] = eqx.field(converter=_chip_pairs)
    depth: Float[Array, ""]
    noise: Float[Array, "3"]
    hall: Hall3D
    effects: tuple[AbstractEffect, ...]
    direction: tuple[float, float, float] = eqx.field(static=True, default=(0.0, 0.0, 1.0))
    cells: tuple[int, int, int] = eqx.field(static=True, default=(16, 16, 8))
    map_grid: tuple[int, int] = eqx.field(static=True, default=(5, 5))
    map_size: tuple[float, float] | None = eqx.field(static=True, default=None)
    spectral: SpectralGrid | None = eqx.field(static=True, default=None)
    pitch: Float[Array, ""] | None = None
    magnets: SkinMagnets | None = None
    field: str = eqx.field(static=True, default="linear")
    resolution: tuple[int, int, int] | None = eqx.field(static=True, default=None)
    indenter: str = eqx.field(static=True, default="sphere")
    soft: tuple[SoftPart, ...] = ()
    period: Float[Array, ""] | None = None
    material: str = eqx.field(static=True, default="linear")
    bulk_modulus: Float[Array, ""] | None = None

    def __post_init__(self):
        if self.material not in LAYER_MATERIALS:
            raise ValueError(f"material must be one of {LAYER_MATERIALS}, got {self.material!r}")
        if self.material == "neo_hookean" and (self.bulk_modulus is None or self.indenter != "sphere"):
            raise ValueError("a neo_hookean layer needs its bulk_modulus and a sphere (indenter 'sphere')")
        if self.field not in FIELD_MODELS:
            raise ValueError(f"field must be one of {FIELD_MODELS}, got {self.field!r}")
        if self.indenter not in INDENTERS:
            raise ValueError(f"indenter must be one of {tuple(INDENTERS)}, got {self.indenter!r}")
        if self.period is not None and (self.magnets is not None or self.direction[1] != 0.0):
            raise ValueError(
                "period: the pattern turns the layer's polarization in the x-z plane; expected no magnets and a "
                f"direction without a y component, got {self.direction!r}"
            )
        # the wavevector lattice and the linear field's nodes, from the values at construction
        # (module docstring)
        linear = self.field == "linear" and self.magnets is None
        if linear and self.resolution is None:
            self.resolution = default_resolution(self.size, self.depth, self.period)
        if self.spectral is None and linear:
            self.spectral = linear_grid(self.size, self.thickness, self.resolution)
        elif self.spectral is None:
            self.spectral = spectral_grid(size=self.size, thickness=self.thickness, cells=self.cells)

    SOURCE_KEY: ClassVar = "magnet.polarization"
    reading_labels: ClassVar = ("Bx", "By", "Bz")
    reading_unit: ClassVar = "T"
    output_units: ClassVar[dict[str, str]] = {
        "localisation_worst": "m",
        "localisation_median": "m",
        "force_resolution_normal": "N",
        "force_resolution_shear": "N",
        "force_resolution_shear_x": "N",
        "force_resolution_shear_y": "N",
        "crosstalk": "1",
        "background_force_error": "N",
        "saturation_ratio": "1",
        "saturation_force": "N",
        MECHANICS_CONVERGED: "1",
    }

    @property
    def parameter_paths(self):
        paths = {
            "magnet.polarization": lambda s: s.polarization,
            "mechanics.thickness": lambda s: s.thickness,
            "mechanics.shear_modulus": lambda s: s.shear_modulus,
            "sensor.depth": lambda s: s.depth,
            "indenter.radius": lambda s: s.sphere_radius,
        }
        if self.period is not None:
            paths["magnet.period"] = lambda s: s.period
        if self.pitch is not None:
            paths["sensor.pitch"] = lambda s: s.pitch
        else:
            for i in range(len(self.chips)):
                for k in range(2):
                    paths[f"sensor.chips[{i}][{k}]"] = lambda s, i=i, k=k: s.chips[i][k]
        return paths | soft_parameter_paths(self.soft, lambda s: s.soft)

    def chip_range(self):
        """The listed saturation effect, else the Hall chips' own range per axis."""
        return judged_saturation(self.effects, self.hall.full_scale)

    def chip_positions(self, *, xp=jnp) -> Float[Array, "s 2"]:
        """The chips' (x, y) (m), (S, 2): ``chips``, times ``pitch`` where one is given.
        ``xp``: the array module, ``jax.numpy`` (traceable) or ``numpy`` (a concrete scene's
        numbers without a JAX program: the spec's checks)."""
        positions = xp.stack([xp.stack(chip) for chip in self.chips])
        return positions if self.pitch is None else positions * xp.asarray(self.pitch)

    def sensor_poses(self):
        chips = self.chip_positions()
        positions = jnp.concatenate([chips, jnp.broadcast_to(-self.depth, (chips.shape[0], 1))], axis=-1)
        return positions, jnp.broadcast_to(jnp.eye(3), (positions.shape[0], 3, 3))

    def displacement(self, loads: Loads):
        """The load states (x, y, Fn, F_x, F_y) (m, m, N, N, N), (n, 5), and whether the
        mechanics carries each (n,): always the linear layer; the neo_hookean layer where
        the Newton solve of its press at that Fn converged (the field is NaN where not)."""
        state = jnp.concatenate([loads.contact, loads.normal[:, None], loads.shear], axis=-1)
        if self.material == "linear":
            return state, jnp.ones(state.shape[0], dtype=bool)
        return state, self._press_converged(loads.normal)

    def _press_converged(self, normal_force):
        """Whether the finite-strain layer's press converged under each ``normal_force`` (N, (...,))."""
        return press_converged(normal_force, **self._finite_layer())

    def _finite_layer(self):
        """The finite-strain layer's arguments of press_field and press_converged: the
        sphere, the thickness, the neo-Hookean material and the force floor."""
        return {
            "sphere_radius": self.sphere_radius,
            "thickness": self.thickness,
            "material": NeoHookean(mu=self.shear_modulus, bulk=self.bulk_modulus),
            "force_floor": CONTACT_FORCE_FLOOR,
        }

    def layer(self) -> ElasticLayer:
        return ElasticLayer(
            thickness=self.thickness, shear_modulus=self.shear_modulus, poisson_ratio=self.poisson_ratio
        )

    def layer_motion_grid(self, load: SurfaceLoad, cells, grid, levels=None):
        """Displacement u (m) and rotation curl(u) / 2 (rad), each (n_x, n_y, n_z, 3), at the
        centres of the layer's ``cells`` (or at ``levels``) under ``load``
        (:func:`~magdesign.mechanics.skin_layer.layer_displacement_grid`'s arguments): the
        linear layer's, or with the neo_hookean material the finite-strain layer's press plus
        the linear layer's shear (module docstring)."""
        u, rotation = layer_displacement_grid(
            layer=self.layer(), load=self._linear_part(load), size=self.size, cells=cells, grid=grid, levels=levels
        )
        if self.material == "linear":
            return u, rotation
        nx, ny, nz = cells
        side = self.size / jnp.array([nx, ny])
        x = (jnp.arange(nx) + 0.5) * side[0] - 0.5 * self.size[0]
        y = (jnp.arange(ny) + 0.5) * side[1] - 0.5 * self.size[1]
        heights = (np.arange(nz) + 0.5) / nz if levels is None else np.asarray(levels, dtype=float)
        z = jnp.asarray(heights) * self.thickness
        points = jnp.stack(jnp.meshgrid(x, y, z, indexing="ij"), axis=-1)
        du, drotation = self._press(points, load)
        return u + du, rotation + drotation

    def layer_motion(self, points, load: SurfaceLoad):
        """Displacement u (m), (..., 3), at ``points`` (..., 3) of the layer under ``load``
        (:func:`~magdesign.mechanics.skin_layer.layer_displacement`'s): as :meth:`layer_motion_grid`."""
        u = layer_displacement(points, layer=self.layer(), load=self._linear_part(load))
        return u if self.material == "linear" else u + self._press(points, load)[0]

    def _linear_part(self, load: SurfaceLoad) -> SurfaceLoad:
        """The part of ``load`` that the linear layer carries: all of it, or its shear alone
        where the finite-strain layer carries the press."""
        if self.material == "linear":
            return load
        return eqx.tree_at(lambda l: l.normal_force, load, jnp.zeros_like(load.normal_force))

    def _press(self, points, load: SurfaceLoad):
        """The finite-strain layer's (u, rotation) at ``points`` (..., 3) under the load's
        normal force (NaN where its solve did not converge)."""
        u, rotation, converged = press_field(
            points, centre=load.centre, normal_force=load.normal_force, **self._finite_layer()
        )
        return jnp.where(converged, u, jnp.nan), jnp.where(converged, rotation, jnp.nan)

    def contact_radius(self, normal_force: Float[Array, "..."], *, xp=jnp) -> Float[Array, "..."]:
        """The contact patch's radius a (m) under ``normal_force`` (N, (...,)), shape
        (...,): the sphere's Hertz radius, floored, or the flat punch's own (module
        docstring). ``xp``: the array module (:meth:`chip_positions`)."""
        radius = xp.asarray(self.sphere_radius)
        if self.indenter == "flat":
            return xp.broadcast_to(radius, xp.shape(normal_force))
        e_star = 2.0 * xp.asarray(self.shear_modulus) / (1.0 - xp.asarray(self.poisson_ratio))
        force = xp.maximum(normal_force, CONTACT_FORCE_FLOOR)
        return (3.0 * force * radius / (4.0 * e_star)) ** (1.0 / 3.0)

    def contact_strain(
        self, normal_force: Float[Array, "..."], shear_force: Float[Array, "... 2"], *, xp=jnp, press=True
    ) -> Float[Array, "..."]:
        """The strain under the contact (-), shape (...,): the displacement of the patch's
        centre, its depth delta and its tangential travel u_t, over the patch's radius a,
        |(delta, u_t)| / a, for a ``normal_force`` Fn (N, (...,)) and a ``shear_force``
        (F_x, F_y) (N, (..., 2)), from the half-space's closed forms (Johnson, "Contact
        Mechanics", 1985, ch. 3 and 7) with G the shear modulus:

        - the sphere's Hertz patch: delta = 3 Fn (1 - nu) / (8 G a) = a^2 / R, so delta / a =
          a / R, the slope of the pressed surface at the patch's edge, the largest gradient
          of its displacement; the traction of Hertz's shape moves the centre by
          u_t = 3 |F_t| (2 - nu) / (16 G a) (a slipping contact's; where the patch sticks,
          the centre moves two thirds of it: Johnson, sec. 7.2);
        - the flat punch: delta = Fn (1 - nu) / (4 G a), u_t = |F_t| (2 - nu) / (8 G a)
          (the punch's face moves as one), the mean gradient under it (its edge is singular).

        On a bonded layer the depth is smaller than the half-space's (by 7 % at a / h = 0.1,
        22 % at 0.3: :mod:`magdesign.mechanics.skin_layer`), so this overstates the strain
        a little there. ``xp``: the array module (:meth:`chip_positions`). ``press``: False
        leaves the depth out, the tangential travel alone on the press's patch |u_t| / a."""
        radius = self.contact_radius(normal_force, xp=xp)
        g, nu = xp.asarray(self.shear_modulus), xp.asarray(self.poisson_ratio)
        shape = 1.5 if self.indenter == "sphere" else 1.0  # Hertz's centre over the flat punch's
        tangential = (2.0 - nu) * xp.asarray(shear_force, dtype=float)
        normal = ((2.0 * (1.0 - nu) if press else 0.0) * xp.asarray(normal_force, dtype=float))[..., None]
        travels = xp.concatenate([normal, tangential], axis=-1)
        # traced: a finite slope at rest too; numpy's numbers need no derivative
        travel = safe_norm(travels) if xp is jnp else np.linalg.norm(travels, axis=-1)
        return shape * travel / (8.0 * g * radius * radius)

    def surface_load(self, state: Float[Array, "5"]) -> SurfaceLoad:
        """The indenter's load of a load state (x, y, Fn, F_x, F_y) (m, m, N, N, N)."""
        return SurfaceLoad(
            centre=state[:2],
            radius=self.contact_radius(state[2]),
            normal_force=state[2],
            shear_force=state[3:5],
            profile=INDENTERS[self.indenter],
        )

    def linear_field(self, points, load: SurfaceLoad, resolution=None):
        """The magnetised layer's field B (T) at ``points`` (m, (..., 3)) under
        ``load``, first order in the displacement (:func:`magdesign.fields.layer_field.layer_field`),
        at ``resolution`` (n_x, n_y, Gauss nodes; static): the scene's, or its :func:`finer`
        one (the lattice's periods, a length, kept)."""
        resolution = self.resolution if resolution is None else tuple(resolution)
        factor = resolution[0] // self.resolution[0]
        grid = self.spectral
        if resolution != self.resolution:
            grid = band_limited_grid(tuple(factor * p for p in grid.periods), resolution[2])
        heights, _ = gauss_levels(resolution[2])
        u, rotation = self.layer_motion_grid(load, resolution, grid, tuple(heights))
        return layer_field(
            points,
            size=self.size,
            thickness=self.thickness,
            polarization=self.polarization * jnp.asarray(self.direction),
            displacement=u,
            rotation=rotation,
            period=self.period,
        )

    def field_error(self, state: Float[Array, "5"]) -> Float[Array, "s 3"]:
        """The linear field's discretisation error at the chips (T, scene frame), (S, 3),
        under one load state (x, y, Fn, F_x, F_y): its change from the scene's resolution to
        the :func:`~magdesign.fields.layer_field.finer` one (module docstring)."""
        if self.field != "linear" or self.magnets is not None:
            raise ValueError("field_error: only a magnetised layer's linear field has an estimate")
        points, _ = self.sensor_poses()
        load = self.surface_load(state)
        coarse = self.linear_field(points, load)
        return jnp.abs(self.linear_field(points, load, finer(self.resolution)) - coarse)

    def source_field(self, points, displacement):
        field = self.skin_field(points, displacement)
        if self.soft:
            # fixed parts (nearby iron), magnetised by the skin's field under the same load
            field = field + soft_parts_field(
                self.soft, points, jnp.zeros(3), lambda x: self.skin_field(x, displacement)
            )
        return field

    def skin_field(self, points, displacement):
        """The skin's own flux density (T, scene frame) at ``points`` (m, (..., 3)) under the
        load state ``displacement`` (x, y, Fn, F_x, F_y): the layer's or its magnets'."""
        load = self.surface_load(displacement)
        if self.magnets is None and self.field == "linear":
            return self.linear_field(points, load)
        if self.magnets is not None:
            # the discrete magnets, each carried by the layer's displacement and rotation at its centre
            dimension = self.magnets.sizes
            moved, turned = moved_cells(
                self.magnets.centres,
                self.polarization * self.magnets.directions,
                lambda x: self.layer_motion(x, load),
            )
        else:
            centres, dimension = layer_cells(size=self.size, thickness=self.thickness, cells=self.cells)
            polarization = jnp.broadcast_to(self.polarization * jnp.asarray(self.direction), centres.shape)
            if self.period is not None:
                polarization = pattern(centres[:, 0], self.period, polarization[0])
            u, rotation = self.layer_motion_grid(load, self.cells, self.spectral)
            moved, turned = carried_cells(centres, polarization, u.reshape(-1, 3), rotation.reshape(-1, 3))
        return cells_field(points, centres=moved, dimension=dimension, polarization=turned)

    def transduce(self, field):
        return field

    def map_points(self, *, xp=jnp) -> Float[Array, "m 2"]:
        """The outputs' contact positions (M, 2) (m): a ``map_grid`` over the ``map_size``
        area centred on the skin's centre (the origin), or where it is None over the chips'
        bounding box, corners included; along an axis of one point, the area's middle.
        ``xp``: the array module (:meth:`chip_positions`)."""
        if self.map_size is None:
            chips = self.chip_positions(xp=xp)
            low, high = xp.min(chips, axis=0), xp.max(chips, axis=0)
        else:
            high = xp.asarray(self.map_size) / 2
            low = -high
        xs, ys = (
            xp.linspace(low[i], high[i], n) if n > 1 else ((low[i] + high[i]) / 2)[None]
            for i, n in enumerate(self.map_grid)
        )
        xx, yy = xp.meshgrid(xs, ys, indexing="ij")
        return xp.stack([xx.ravel(), yy.ravel()], axis=-1)

    def readings_at(self, state: Float[Array, "5"]) -> Float[Array, "s 3"]:
        """Every chip's field (T, chip frame), (S, 3), under one load state (x, y, Fn, F_x,
        F_y): the scene's static chain (its chips placed and tilted, the source's and the
        field's effects) up to the readings' own effects, whose noise the bounds take."""
        return chain(self, state[None], without=STATIC_WITHOUT).chip_field[0]

    def background_reference(self) -> Float[Array, ""]:
        """The size (T) of the uniform field whose force error ``background_force_error``
        states: |B| of the listed background effects' field (the field the chips sit in),
        else BACKGROUND_REFERENCE (the Earth's, 50 uT). A stated zero field gives 0."""
        stated = [effect.field_ for effect in self.effects if isinstance(effect, Background)]
        return safe_norm(sum(stated)) if stated else jnp.asarray(BACKGROUND_REFERENCE)

    def resolution_at(self, state: Float[Array, "5"]):
        """(Cramer-Rao :class:`~magdesign.inverse.Bound` of the load state from all readings,
        the normal-force error (N) of a uniform field of :meth:`background_reference`'s size
        along x, y and z (3,))."""
        jacobian = jax.jacfwd(lambda q: self.readings_at(q).ravel())(state)  # (3 S, 5)
        noise = jnp.tile(self.noise, len(self.chips))
        bound = cramer_rao(jacobian, noise)
        # the least-squares fit's response to a uniform field added to every chip
        weighted = jacobian / noise[:, None]
        fields = jnp.tile(jnp.eye(3) * self.background_reference(), (1, len(self.chips))) / noise  # (3, 3 S)
        shift = jnp.einsum("ij,kj->ki", bound.covariance @ weighted.T, fields)
        return bound, shift[:, 2]

    def range_fractions(self, state: Float[Array, "5"]) -> Float[Array, " k"]:
        """Every chip axis's reading (:meth:`readings_at`) over its range (-), (3 S,), under
        one load state (x, y, Fn, F_x, F_y)."""
        return (self.readings_at(state) / self.chip_range().limit).ravel()

    def saturation_force_at(
        self, contact: Float[Array, "2"], shear_ratio: Float[Array, "2"], start: Float[Array, ""]
    ) -> Float[Array, ""]:
        """The largest normal force F (N) pressing at ``contact`` (m, (2,)), with the shear
        F ``shear_ratio`` (-, (2,)), before a chip axis leaves its range: the secant search
        from ``start`` (N, > 0) and its last Newton step (module docstring)."""
        held, point, ratio = _held(self), jax.lax.stop_gradient(contact), jax.lax.stop_gradient(shear_ratio)

        def fractions(scene, force, at=point):
            return scene.range_fractions(jnp.concatenate([at, force[None], force * ratio]))

        rest = fractions(held, jnp.zeros(()))

        def secant(carry):
            step, force, _ = carry
            crossing = jnp.min(first_crossings(rest, (fractions(held, force) - rest) / force))
            return step + 1, jnp.clip(crossing, CONTACT_FORCE_FLOOR, SATURATION_FORCE_CAP), force

        def moving(carry):
            step, force, last = carry
            return (step < SATURATION_STEPS) & (jnp.abs(force - last) > SATURATION_RTOL * force)

        start = jnp.clip(jax.lax.stop_gradient(start), CONTACT_FORCE_FLOOR, SATURATION_FORCE_CAP)
        _, force, _ = jax.lax.while_loop(moving, secant, (0, start, jnp.asarray(jnp.inf)))
        # the binding axis at the answer, and its slope there, held fixed: one evaluation of
        # the readings gives the Newton step's values (their derivative the answer's) and,
        # held, the slopes and the axis
        current, slopes = jax.jvp(lambda f: fractions(self, f, contact), (force,), (jnp.ones(()),))
        values, slopes = jax.lax.stop_gradient(current), jax.lax.stop_gradient(slopes)
        axis = jnp.argmin(first_crossings(rest, (values - rest) / force))
        bound = jnp.sign(values[axis])
        newton = force - safe_div(current[axis] - bound, slopes[axis])
        return jnp.where(jnp.max(jnp.abs(rest)) >= 1.0, 0.0, jnp.where(force >= SATURATION_FORCE_CAP, force, newton))

    def saturation_force(self, loads: Loads) -> Float[Array, ""]:
        """The output ``saturation_force`` (N) of a sweep ``loads``: the smallest
        :meth:`saturation_force_at` over the map's points and the sweep's contacts, pressing
        along the sweep's load of largest normal force (module docstring)."""
        largest = jnp.argmax(loads.normal)
        force = loads.normal[largest]
        ratio = safe_div(loads.shear[largest], force)
        contacts = jnp.concatenate([self.map_points(), loads.contact], axis=0)
        concrete = _concrete(contacts)
        if concrete is not None:  # the same contact pressed at several forces counts once
            contacts = jnp.asarray(np.unique(concrete, axis=0))
        return jnp.min(jax.lax.map(lambda point: self.saturation_force_at(point, ratio, force), contacts))

    def outputs(self, result):
        force = jnp.max(result.loads.normal)
        shear = result.loads.shear[jnp.argmax(result.loads.normal)]
        states = jnp.concatenate(
            [
                self.map_points(),
                jnp.broadcast_to(jnp.concatenate([force[None], shear]), (self.map_points().shape[0], 3)),
            ],
            axis=-1,
        )
        bounds, background = jax.lax.map(self.resolution_at, states)
        variance = jnp.diagonal(bounds.covariance, axis1=-2, axis2=-1)  # (M, 5)
        localisation = jnp.sqrt(variance[:, 0] + variance[:, 1])
        correlation = bounds.covariance[:, 2, 3:5] / jnp.sqrt(variance[:, 2:3] * variance[:, 3:5])
        saturation = self.saturation_force(result.loads)
        converged = jnp.all(result.converged)
        if self.material != "linear":
            # saturation_force's search presses harder than the sweep: a press the layer does not
            # carry on its way leaves it NaN, which mechanics_converged then says
            held = jax.lax.stop_gradient(saturation)
            converged = converged & jnp.isfinite(held) & self._press_converged(held)
        return {
            "localisation_worst": jnp.max(localisation),
            "localisation_median": jnp.median(localisation),
            "force_resolution_normal": jnp.max(bounds.deviation[:, 2]),
            "force_resolution_shear": jnp.max(bounds.deviation[:, 3:5]),
            "force_resolution_shear_x": jnp.max(bounds.deviation[:, 3]),
            "force_resolution_shear_y": jnp.max(bounds.deviation[:, 4]),
            "crosstalk": jnp.max(jnp.abs(correlation)),
            "background_force_error": jnp.max(jnp.abs(background)),
            "saturation_ratio": self.chip_range().ratio(self.transduce(result.chip_field)),
            "saturation_force": saturation,
            MECHANICS_CONVERGED: converged.astype(float),
        }
