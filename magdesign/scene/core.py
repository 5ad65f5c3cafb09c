"""The scene: one sensor design's forward chain, and :func:`simulate`.

    loads --mechanics--> displacement of the source relative to the sensors (n, 3)
          --source-----> flux density at each sensor, scene frame (n, S, 3)
          --chip frame-> the field each chip sees, Rx Ry Rz H (n, S, 3)
          --transducer-> readings (n, S, C)

with the scene's effects (:mod:`magdesign.scene.effects`) hooked in at their stages.
"""

import abc
import warnings
from collections.abc import Callable, Mapping
from typing import ClassVar, NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Bool, Float, PRNGKeyArray

from magdesign._tracing import on_device
from magdesign.scene.effects import AbstractEffect, judged_saturation
from magdesign.scene.loads import Loads
from magdesign.transducers import to_chip
from magdesign.units import SpecError

# Name of the scene output that is 1 where the mechanics' solve converged and 0 where it
# did not (a design solve reports the latter as "mechanics_not_converged").
MECHANICS_CONVERGED = "mechanics_converged"


class AbstractScene(eqx.Module):
    """A sensor design: a magnetic source, its mechanics, sensors, and effects.

    Concrete scenes hold their numeric parameters as float64 array leaves (see
    :func:`parameters`) and their configuration (fidelity, sensor count, effect list)
    as static structure. Subclasses give:

    - ``parameter_paths``: dotted spec key -> accessor of the leaf in the scene;
    - ``SOURCE_KEY``: the parameter that the temperature drift scales;
    - ``reading_labels`` / ``reading_unit``: names of the C reading channels and their unit;
    - ``output_units``: each name :meth:`outputs` returns -> its SI unit, as a string
      :func:`magdesign.units.parse` reads ("m/N", "T", "1", ...).
    """

    effects: eqx.AbstractVar[tuple[AbstractEffect, ...]]
    SOURCE_KEY: ClassVar[str]
    reading_labels: ClassVar[tuple[str, ...]]
    reading_unit: ClassVar[str]
    output_units: ClassVar[dict[str, str]]

    @property
    @abc.abstractmethod
    def parameter_paths(self) -> dict[str, Callable]:
        """Dotted spec key -> accessor of that parameter's leaf in the scene."""

    @abc.abstractmethod
    def sensor_poses(self) -> tuple[Float[Array, "s 3"], Float[Array, "s 3 3"]]:
        """Nominal sensor positions (S, 3) (m) and chip rotations (S, 3, 3), scene frame."""

    @abc.abstractmethod
    def displacement(self, loads: Loads) -> tuple[Float[Array, "n 3"], Bool[Array, " n"]]:
        """Displacement (m) of the source relative to the sensors at each load point, and
        whether the mechanics' solve converged there (n,)."""

    @abc.abstractmethod
    def source_field(self, points: Float[Array, "... 3"], displacement: Float[Array, "3"]) -> Float[Array, "... 3"]:
        """Flux density (T) of the displaced source at ``points`` (m), scene frame."""

    @abc.abstractmethod
    def transduce(self, field: Float[Array, "n s 3"]) -> Float[Array, "n s c"]:
        """Ideal readings (``reading_unit``) from the field in each chip's frame (T)."""

    @abc.abstractmethod
    def outputs(self, result: "SimulationResult") -> dict[str, Float[Array, ""]]:
        """Named scalar outputs (SI) for design targets, read from a simulation of the
        scene (:func:`outputs`); see each scene."""

    def chip_range(self) -> AbstractEffect | None:
        """The range the readings are judged against (:func:`magdesign.scene.effects.judged_saturation`):
        the listed saturation effect, else the chip's own range where the scene knows it; None
        where it knows none."""
        return judged_saturation(self.effects)

    def probe_points(self) -> Float[Array, "e 3"] | None:
        """Points (E, 3) (m) besides the sensors whose field :meth:`extras` needs (e.g.
        inductors), evaluated in the same batched field call as the sensors'; or None."""
        return None

    def extras(
        self,
        displacement: Float[Array, "n 3"],
        loads: Loads,
        probe_field: Float[Array, "n e 3"] | None,
        key: PRNGKeyArray | None = None,
    ) -> dict[str, Array]:
        """Further read-outs of a simulation (e.g. inductor EMF, slip flags), given the
        field (T, scene frame, no field effects) at :meth:`probe_points`; ``key`` draws
        their own noise (None: noiseless)."""
        return {}


class SimulationResult(eqx.Module):
    """The forward chain over a load sweep.

    Attributes:
        loads: the load sweep (n points).
        displacement: (n, 3) source displacement relative to the sensors (m).
        field: (n, S, 3) flux density at each sensor in the scene frame, with the
            field effects applied (T).
        chip_field: (n, S, 3) the same in each chip's own frame (a, b, c) (T): what the
            transducer reads before its own non-idealities.
        readings: (n, S, C) transducer readings with all effects (reading unit).
        extras: further named arrays (scene-specific).
        converged: (n,) whether the mechanics' solve converged at each load point; where
            it did not, the row's numbers are not an equilibrium.
        labels: names of the C reading channels; unit: their unit (static).
    """

    loads: Loads
    converged: Bool[Array, " n"]
    displacement: Float[Array, "n 3"]
    field: Float[Array, "n s 3"]
    chip_field: Float[Array, "n s 3"]
    readings: Float[Array, "n s c"]
    extras: dict[str, Array]
    labels: tuple[str, ...] = eqx.field(static=True)
    unit: str = eqx.field(static=True)


def parameters(scene: AbstractScene) -> dict[str, Float[Array, ""]]:
    """The scene's numeric parameters by dotted spec key (SI float64 arrays)."""
    return {name: get(scene) for name, get in scene.parameter_paths.items()}


def with_parameters(scene: AbstractScene, values: Mapping[str, ArrayLike]) -> AbstractScene:
    """A copy of ``scene`` with the named parameters replaced (traceable: jit/grad/vmap).

    Raises:
        SpecError: a name that is not one of the scene's parameters.
    """
    paths = scene.parameter_paths
    for name in values:
        if name not in paths:
            raise SpecError(f"{name}: unknown parameter; expected one of: {', '.join(paths)}")
    if not values:
        return scene
    names = list(values)
    getters = [paths[name] for name in names]
    replacements = [_float_array(values[name]) for name in names]
    return eqx.tree_at(lambda s: [get(s) for get in getters], scene, replacements)


def _float_array(value):
    """``value`` as a float64 jax array (strongly typed); a number or numpy array without a
    program to compile (:func:`magdesign._tracing.on_device`)."""
    if isinstance(value, jax.Array):  # a tracer too
        return jnp.asarray(value, dtype=jnp.result_type(float))
    return on_device(np.asarray(value, dtype=jnp.result_type(float)))


def apply_source_effects(scene: AbstractScene, effects) -> AbstractScene:
    """The scene with the source effects among ``effects`` applied to its source's strength."""
    for effect in effects:
        scale = effect.source_scale()
        if scale is not None:
            strength = scene.parameter_paths[scene.SOURCE_KEY](scene)
            scene = with_parameters(scene, {scene.SOURCE_KEY: strength * scale})
    return scene


class Chain(NamedTuple):
    """One pass of the forward chain (see :func:`chain`); n load points, S sensors."""

    displacement: Float[Array, "n 3"]  # after the motion effects (m)
    field: Float[Array, "n s 3"]  # at the sensors, scene frame, with the field effects (T)
    chip_field: Float[Array, "n s 3"]  # the same in each chip's frame (a, b, c) (T)
    readings: Float[Array, "n s c"]  # with the reading effects (reading unit)
    probe_field: Float[Array, "n e 3"] | None  # at the probe points, no field effects (T)


# Effects that are random: a design leaves them out.
RANDOM_EFFECTS = ("noise",)
# Left out for the static, deterministic chain at a single load (a derivative at rest, an
# inversion): the random effects and the lag, which needs a time series.
STATIC_WITHOUT = ("noise", "viscoelastic_lag")


def chain(
    scene: AbstractScene,
    displacement: Float[Array, "n 3"],
    *,
    time: Float[Array, " n"] | None = None,
    key: PRNGKeyArray | None = None,
    without: tuple[str, ...] = (),
) -> Chain:
    """The chain from the source's displacement (n, 3) (m) on (:class:`Chain`).

    Effects named in ``without`` are left out (the inverse leaves out "noise" and
    "viscoelastic_lag" to get the deterministic, static forward model).
    """
    effects = tuple(effect for effect in scene.effects if effect.name not in without)
    scene = apply_source_effects(scene, effects)
    positions, rotations = scene.sensor_poses()
    for effect in effects:
        positions, rotations = effect.sensors(positions, rotations)
    positions = jnp.broadcast_to(positions, rotations.shape[:-1])
    for effect in effects:
        displacement = effect.motion(displacement, time)

    # Each sensor reads the field at its centre, or averaged over a sampling effect's nodes.
    sensors = positions.shape[0]
    samplings = [sampling for effect in effects if (sampling := effect.sampling(rotations)) is not None]
    points = positions if not samplings else (positions[:, None, :] + samplings[0][0]).reshape(-1, 3)
    count = points.shape[0]
    probes = scene.probe_points()
    if probes is not None:
        points = jnp.concatenate([points, probes])
    raw = jax.vmap(lambda u: scene.source_field(points, u))(displacement)
    field, probe_field = raw[:, :count], (None if probes is None else raw[:, count:])
    if samplings:
        weights = samplings[0][1]
        field = jnp.einsum("q,nsqi->nsi", weights, field.reshape(-1, sensors, weights.shape[0], 3))
    for effect in effects:
        field = effect.field(field)

    chip_field = to_chip(rotations, field)
    readings = scene.transduce(chip_field)
    for effect in effects:
        readings = effect.reading(readings, key)
    return Chain(displacement, field, chip_field, readings, probe_field)


@eqx.filter_jit
def simulate(
    scene: AbstractScene, loads: Loads, *, key: PRNGKeyArray | None = None, without: tuple[str, ...] = ()
) -> SimulationResult:
    """Run the scene's forward chain over ``loads``, with exactly the scene's effects (jitted).

    ``key`` (a JAX PRNG key) is needed when the scene lists ``noise``, and draws the noise of
    further read-outs (the inductors'); without it they are noiseless. Effects named in
    ``without`` are left out (with "noise", the further read-outs are noiseless too).
    """
    displacement, converged = scene.displacement(loads)
    passed = chain(scene, displacement, time=loads.time, key=key, without=without)
    extras_key = None if key is None or "noise" in without else jax.random.fold_in(key, 1)
    extras = scene.extras(passed.displacement, loads, passed.probe_field, extras_key)
    return SimulationResult(
        loads,
        converged,
        passed.displacement,
        passed.field,
        passed.chip_field,
        passed.readings,
        extras,
        scene.reading_labels,
        scene.reading_unit,
    )


def outputs(scene: AbstractScene, loads: Loads) -> dict[str, Float[Array, ""]]:
    """The scene's named scalar outputs (SI) over the load sweep ``loads``: what
    :meth:`AbstractScene.outputs` reads from :func:`simulate` of that sweep (its random
    effects left out; no output reads the readings after the reading effects, so that
    noise, clipping and rounding change none). Traceable and differentiable."""
    return scene.outputs(simulate(scene, loads, without=RANDOM_EFFECTS))


def _si_to_display(unit):
    """A display unit and its factor for an SI unit name."""
    return {"T": ("mT", 1e3), "V": ("mV", 1e3), "m": ("mm", 1e3), "N": ("N", 1.0)}.get(unit, (unit, 1.0))


# A chip's saturation_ratio counts as clipping above 1 + CLIP_RTOL: a design held at its chip's
# range reads 1 to the design solver's tolerance (DESIGN_RTOL), far below this.
CLIP_RTOL = 1e-6
# The saturation_ratio above which the chip is said to clip.
CLIPS_ABOVE = 1.0 + CLIP_RTOL


class ClippingWarning(UserWarning):
    """A simulation whose chip clips: a reading beyond the chip's range
    (:meth:`AbstractScene.chip_range`)."""


def saturation_ratio(scene: AbstractScene, result: SimulationResult) -> float | None:
    """The largest |reading| / range of a simulation of ``scene`` (-), over every load
    point, sensor and channel, from the readings before the reading effects (the
    transducer's reading of ``result.chip_field``), the range :meth:`AbstractScene.chip_range`'s;
    None where the scene knows no range. Above 1 the chip clips."""
    judged = scene.chip_range()
    if judged is None:
        return None
    # on the host: numpy copies of the range and the readings, no program to compile
    return float(jax.tree.map(np.asarray, judged).ratio(np.asarray(scene.transduce(result.chip_field))))


def warn_if_clipping(scene: AbstractScene, result: SimulationResult) -> None:
    """A :class:`ClippingWarning` (one line) where a simulation's chip clips
    (:func:`saturation_ratio` above :data:`CLIPS_ABOVE`)."""
    ratio = saturation_ratio(scene, result)
    if ratio is not None and ratio > CLIPS_ABOVE:
        listed = any(effect.name == "saturation" for effect in scene.effects)
        shown = (
            "the readings beyond it stop at the limit"
            if listed
            else "the scene does not list the saturation effect, so its readings here go beyond it"
        )
        warnings.warn(
            f"the chip clips: its largest reading is {ratio:.3g} times its range (saturation_ratio); {shown}",
            ClippingWarning,
            stacklevel=2,
        )


def simulation_table(result: SimulationResult) -> str:
    """A readable table: one row per load point, forces (N), displacement (mm), the chips'
    readings (after the transducer and the reading effects: "s0.Bz reading" is sensor 0's
    reading of its c axis, clipped and rounded where the scene lists those effects); then
    a warning naming the load points where the mechanics did not converge."""
    unit, factor = _si_to_display(result.unit)
    readings = np.asarray(result.readings) * factor
    n, sensors, channels = readings.shape
    loads = result.loads
    header = ["t (s)", "Fz (N)", "Fx (N)", "Fy (N)"]
    if np.shape(result.displacement)[-1] == 3:  # the source's displacement
        header += ["ux (mm)", "uy (mm)", "uz (mm)"]
        u = np.asarray(result.displacement) * 1e3
    else:  # a scene whose mechanics' state is the load itself (a skin): show the contact point
        header += ["x (mm)", "y (mm)"]
        u = np.asarray(loads.contact) * 1e3
    names = [f"s{s}.{label}" for s in range(sensors) for label in result.labels]
    header += [f"{name} reading ({unit})" for name in names]
    rows = []
    for i in range(n):
        row = [loads.time[i], loads.normal[i], loads.shear[i, 0], loads.shear[i, 1], *u[i], *readings[i].ravel()]
        rows.append([f"{float(value):.6g}" for value in row])
    widths = [max(len(h), *(len(r[j]) for r in rows)) for j, h in enumerate(header)]
    lines = ["  ".join(h.rjust(w) for h, w in zip(header, widths))]
    lines += ["  ".join(v.rjust(w) for v, w in zip(row, widths)) for row in rows]
    for name, value in result.extras.items():
        lines.append(f"{name}: {np.array2string(np.asarray(value), precision=6)}")
    failed = np.flatnonzero(~np.asarray(result.converged))
    if failed.size:
        rows_failed = ", ".join(f"{i + 1} (Fz {float(loads.normal[i]):.6g} N)" for i in failed)
        lines.append(
            f"warning: the mechanics did not converge at load points {rows_failed}: those rows are not equilibria"
        )
    return "\n".join(lines)


def simulation_json(result: SimulationResult) -> dict:
    """The result as plain JSON data (SI floats, nested lists)."""
    loads = result.loads
    return {
        "units": {
            "time": "s",
            "normal": "N",
            "shear": "N",
            "contact": "m",
            # a skin's mechanics' state is its load: contact (x, y) (m), then Fn, F_x, F_y (N)
            "displacement": "m" if np.shape(result.displacement)[-1] == 3 else "m, m, N, N, N",
            "field": "T",
            "readings": result.unit,
        },
        "labels": list(result.labels),
        "time": np.asarray(loads.time).tolist(),
        "normal": np.asarray(loads.normal).tolist(),
        "shear": np.asarray(loads.shear).tolist(),
        "contact": np.asarray(loads.contact).tolist(),
        "displacement": np.asarray(result.displacement).tolist(),
        "field": np.asarray(result.field).tolist(),
        "readings": np.asarray(result.readings).tolist(),
        "converged": np.asarray(result.converged).tolist(),
        "extras": {name: np.asarray(value).tolist() for name, value in result.extras.items()},
    }
