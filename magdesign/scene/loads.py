"""Load sweeps and time series: what presses on a sensor, point by point."""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from magdesign.spec.sizes import check_fits
from magdesign.spec.table import Table
from magdesign.units import SpecError


class Loads(eqx.Module):
    """A sequence of n load points, each a time, forces and a contact position.

    Attributes:
        time: (n,) instants (s); a quasi-static sweep uses 0, 1, 2, ... s.
        normal: (n,) normal force (N), positive pressing the sensor.
        shear: (n, 2) shear force (x, y) (N).
        contact: (n, 2) contact position (x, y) on the surface (m); scenes with a
            uniform layer take the load as uniform and do not use it.
    """

    time: Float[Array, " n"]
    normal: Float[Array, " n"]
    shear: Float[Array, "n 2"]
    contact: Float[Array, "n 2"]

    def __init__(self, normal, shear=None, contact=None, time=None):
        self.normal = jnp.asarray(normal, dtype=float)
        n = self.normal.shape[0]
        self.shear = jnp.zeros((n, 2)) if shear is None else jnp.broadcast_to(jnp.asarray(shear, dtype=float), (n, 2))
        self.contact = (
            jnp.zeros((n, 2)) if contact is None else jnp.broadcast_to(jnp.asarray(contact, dtype=float), (n, 2))
        )
        self.time = jnp.arange(n, dtype=float) if time is None else jnp.asarray(time, dtype=float)

    @property
    def max_normal(self) -> Float[Array, ""]:
        """The sweep's largest normal force (N)."""
        return jnp.max(self.normal)


def _sweep(table, key, unit, count):
    """A quantity ramped linearly over ``count`` points from a [start, stop] pair."""
    pair = table.quantities(key, unit, length=2, default=None)
    return np.zeros(count) if pair is None else np.linspace(*pair, count)


# Values a load point carries: normal, shear (2), contact (2), time, and the displacement (3)
# and readings that a simulation of it gives.
LOAD_COLUMNS = 12


def loads_from_spec(spec: dict) -> Loads:
    """The [load] table as a :class:`Loads` sweep.

    Keys (all optional, ranges as [start, stop] with units, ramped linearly):
    ``normal`` (N), ``shear_x``, ``shear_y`` (N), ``contact_x``, ``contact_y`` (m),
    ``points`` (default 11), ``duration`` (s; default: one second per point, i.e. a
    quasi-static sweep). Without a [load] table the sweep is a single unloaded point.
    """
    table = Table(spec, "load", required=False)
    points = table.integer("points", default=11)
    check_fits(f"load.points = {points}", points * LOAD_COLUMNS, what="the load sweep's arrays")
    normal = _sweep(table, "normal", "N", points)
    shear = np.stack([_sweep(table, "shear_x", "N", points), _sweep(table, "shear_y", "N", points)], axis=-1)
    contact = np.stack([_sweep(table, "contact_x", "m", points), _sweep(table, "contact_y", "m", points)], axis=-1)
    duration = table.quantity("duration", "s", default=float(points - 1))
    table.done()
    if duration <= 0.0 and points > 1:
        raise SpecError(f"load.duration: expected a positive time, got {duration!r}")
    return Loads(normal, shear, contact, np.linspace(0.0, duration, points))
