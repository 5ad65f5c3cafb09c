"""A scene's magnets and sensors as magpylib objects (the optional extra ``magpylib``).

For users who want magpylib's own 3-D display (``magpylib.show``) or its other sources
beside a magdesign scene. magpylib stays out of magdesign's core dependencies: it is
imported when :func:`to_magpylib` is first called (``pip install magdesign[magpylib]``).
"""

from typing import NamedTuple

import numpy as np

from magdesign.scene.magnet_scene import MagnetScene
from magdesign.scene.pole_scene import PoleScene
from magdesign.scene.pose import rotation


class MagpylibObjects(NamedTuple):
    """``sources``: a magpylib.Collection of the scene's magnets at rest; ``sensors``: one
    magpylib.Sensor per chip, at its position and orientation (so that
    ``magpylib.getB(sources, sensors)`` gives the field in each chip's frame, in T)."""

    sources: object
    sensors: list


def _magpylib():
    try:
        import magpylib  # noqa: PLC0415 (optional extra: imported on first use only)
        from scipy.spatial.transform import Rotation  # noqa: PLC0415 (a dependency of magpylib)
    except ImportError as error:
        raise ImportError("to_magpylib needs magpylib: pip install 'magdesign[magpylib]'") from error
    return magpylib, Rotation


def _orientation(Rotation, angles):
    """magpylib's orientation (body -> scene) of a body whose angles map scene -> body."""
    matrix = np.eye(3) if angles is None else np.asarray(rotation(angles))
    return Rotation.from_matrix(matrix.T)


def _sensor_poses(scene):
    """Chip positions (S, 3) and rotations (S, 3, 3) with the scene's sensor effects
    (placement, chip tilt), as the forward chain uses them."""
    positions, rotations = scene.sensor_poses()
    for effect in scene.effects:
        positions, rotations = effect.sensors(positions, rotations)
    positions = np.broadcast_to(np.asarray(positions), np.shape(rotations)[:-1])
    return positions, np.asarray(rotations)


def to_magpylib(scene) -> MagpylibObjects:
    """The scene's magnets (at rest) and sensors as magpylib objects, in metres and tesla.

    Supported: :class:`~magdesign.scene.MagnetScene` (every cylinder with its polarization
    and pose) and :class:`~magdesign.scene.PoleScene` (its magnet plate and GMR chip; the
    pole's induced magnetisation has no magpylib counterpart and is left out).

    Raises:
        ValueError: a scene with no magpylib counterpart (the sinusoidal film of
            :class:`~magdesign.scene.FilmScene`).
        ImportError: magpylib is not installed.
    """
    magpylib, Rotation = _magpylib()
    if isinstance(scene, MagnetScene):
        direction = np.array([0.0, 0.0, 1.0]) if scene.direction is None else np.asarray(scene.direction)
        magnets = [
            magpylib.magnet.Cylinder(
                polarization=float(scene.remanence) * direction,
                dimension=(2 * float(scene.radius), float(scene.height)),
                position=np.asarray(scene.magnet_centre()),
                orientation=_orientation(Rotation, scene.angles),
            )
        ]
        for extra in scene.extra:
            magnets.append(
                magpylib.magnet.Cylinder(
                    polarization=np.asarray(extra.polarization),
                    dimension=(2 * float(extra.radius), float(extra.height)),
                    position=np.asarray(extra.centre),
                    orientation=_orientation(Rotation, extra.angles),
                )
            )
    elif isinstance(scene, PoleScene):
        magnets = [
            magpylib.magnet.Cylinder(
                polarization=(0.0, 0.0, float(scene.remanence)),
                dimension=(2 * float(scene.plate_radius), float(scene.plate_thickness)),
                position=(0.0, 0.0, -0.5 * float(scene.plate_thickness)),
            )
        ]
    else:
        raise ValueError(f"to_magpylib: magpylib has no source for a {type(scene).__name__} (a sinusoidal film)")
    positions, rotations = _sensor_poses(scene)
    sensors = [
        magpylib.Sensor(position=position, orientation=Rotation.from_matrix(matrix.T))
        for position, matrix in zip(positions, rotations)
    ]
    return MagpylibObjects(magpylib.Collection(*magnets), sensors)
