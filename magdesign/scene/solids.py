"""The solid bodies of a scene at rest, for the load-time check that every sensor lies
outside every body and that the bodies lie apart.

A body is a cylinder, a sphere or a cuboid at a centre, turned by a rotation. Two bodies
overlap where a point inside one lies inside the other: each body is sampled at the
centres of a grid of cells filling it (:data:`SAMPLES` along each side), and a sample
strictly inside the other body (by more than :data:`TOUCHING` of its size) proves the
overlap, so a refusal is never wrong; an overlap thinner than a cell can pass. Bodies that
touch are apart.
"""

from typing import NamedTuple

import numpy as np

from magdesign.units import SpecError

SAMPLES = 12
# A point counts as inside a body when it lies inside the body shrunk by this fraction of
# its size: a sensor on a face, or two faces that touch, are outside.
TOUCHING = 1e-9


class Solid(NamedTuple):
    """One body: ``key`` (the spec's name for it, "magnet", "soft[0]", "pole.ball_radius"),
    ``shape`` ("cylinder", "sphere" or "cuboid"), ``centre`` (3,) (m, scene frame),
    ``half`` (3,) its half extents along its own axes (m: (R, R, D/2) for a cylinder,
    (r, r, r) for a sphere, the half sides for a cuboid), ``turn`` (3, 3) the rotation that
    takes its own frame to the scene's (v_scene = turn v_body)."""

    key: str
    shape: str
    centre: np.ndarray
    half: np.ndarray
    turn: np.ndarray

    def contains(self, points) -> np.ndarray:
        """(N,) whether each of ``points`` (N, 3) (m, scene frame) lies strictly inside."""
        local = (np.asarray(points, float) - self.centre) @ self.turn / (self.half * (1.0 - TOUCHING))
        if self.shape == "sphere":
            return np.linalg.norm(local, axis=-1) < 1.0
        if self.shape == "cylinder":
            return (np.hypot(local[..., 0], local[..., 1]) < 1.0) & (np.abs(local[..., 2]) < 1.0)
        return np.all(np.abs(local) < 1.0, axis=-1)

    def samples(self) -> np.ndarray:
        """(N, 3) points inside the body (m, scene frame): the centre and the centres of a
        grid of SAMPLES^3 cells over its bounding box that lie inside it."""
        axis = (np.arange(SAMPLES) + 0.5) / SAMPLES * 2.0 - 1.0
        grid = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), -1).reshape(-1, 3)
        points = np.concatenate([np.zeros((1, 3)), grid]) * self.half @ self.turn.T + self.centre
        return points[self.contains(points) | (np.arange(len(points)) == 0)]


def solid(key, shape, centre, half, turn=None) -> Solid:
    """A :class:`Solid` from plain numbers; ``turn`` None: the body's axes are the scene's."""
    return Solid(key, shape, np.asarray(centre, float), np.asarray(half, float), np.eye(3) if turn is None else turn)


def check_apart(sensors, solids) -> None:
    """SpecError unless every sensor point lies outside every solid and the solids lie
    apart. ``sensors``: [(key, points (N, 3) m)], the spec key that places each group
    ("sensor.positions", "inductors.positions"); ``solids``: [:class:`Solid`]."""
    for key, points in sensors:
        points = np.asarray(points, float).reshape(-1, 3)
        for body in solids:
            inside = body.contains(points)
            if np.any(inside):
                point = points[np.argmax(inside)] * 1e3
                raise SpecError(
                    f"{key}: the point [{point[0]:g}, {point[1]:g}, {point[2]:g}] mm lies inside {_named(body)}; "
                    "expected every sensor outside the scene's solid parts"
                )
    for i, a in enumerate(solids):
        for b in solids[i + 1 :]:
            inside = b.contains(a.samples())
            if not np.any(inside):
                inside = a.contains(b.samples())
            if np.any(inside):
                raise SpecError(f"{b.key}: it overlaps {_named(a)}; expected solid parts apart")


def _named(body) -> str:
    """ "the magnet (a cylinder centred at [0, 0, 5.5] mm)", "soft[0] (a sphere ...)"."""
    name = {"magnet": "the magnet", "pole.ball_radius": "the ball (pole.ball_radius)"}.get(body.key, body.key)
    return f"{name} (a {body.shape} centred at {_mm(body.centre)} mm)"


def _mm(point) -> str:
    return "[" + ", ".join(f"{v * 1e3:g}" for v in np.asarray(point, float)) + "]"
