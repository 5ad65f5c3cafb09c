"""How a scene's load moves its source: a dome or an elastomer layer.

Each model maps a :class:`~magdesign.scene.Loads` sweep to the source's displacement
(n, 3) (m) relative to the sensors, with whether its solve converged at each load (n,);
pressing (normal force > 0) moves it by -z.
"""

import abc
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float

from magdesign import mechanics
from magdesign.mechanics import AbstractMaterial, LinearElastic, MooneyRivlin, NeoHookean
from magdesign.mechanics.dome import DEFAULT_MESH
from magdesign.scene.loads import Loads

# Spec names (under [mechanics]) of each material's parameters, and their accessors.
MATERIAL_PARAMETERS = {
    MooneyRivlin: {"c10": lambda m: m.c10, "c01": lambda m: m.c01},
    LinearElastic: {"youngs_modulus": lambda m: m.E, "poisson_ratio": lambda m: m.nu},
    NeoHookean: {"shear_modulus": lambda m: m.mu, "bulk_modulus": lambda m: m.bulk},
}


class AbstractMechanics(eqx.Module):
    """A load -> displacement model with named parameters (``PARAMETERS``)."""

    material: eqx.AbstractVar[AbstractMaterial]
    PARAMETERS: ClassVar[dict]
    output_units: ClassVar[dict[str, str]] = {"travel_fraction": "1"}

    @property
    def parameter_paths(self) -> dict:
        """Dotted spec key -> accessor of the leaf in this model."""
        paths = dict(self.PARAMETERS)
        for name, get in MATERIAL_PARAMETERS[type(self.material)].items():
            paths[f"mechanics.{name}"] = lambda m, get=get: get(m.material)
        return paths

    @abc.abstractmethod
    def displacement(self, loads: Loads) -> tuple[Float[Array, "n 3"], Bool[Array, " n"]]:
        """Displacement (m), (n, 3), at each load point, and whether it converged (n,)."""

    @abc.abstractmethod
    def compliance(self, force: Float[Array, ""]) -> tuple[Float[Array, ""], Bool[Array, ""]]:
        """Secant normal compliance (m/N), normal displacement / ``force`` (N), and whether
        it converged."""

    @abc.abstractmethod
    def top(self) -> Float[Array, ""]:
        """The height (m) of the part's top above the sensor plane (z = 0, where its base
        rests) at rest: where a magnet it carries sits at or below."""

    @abc.abstractmethod
    def bottom(self) -> Float[Array, ""]:
        """The height (m) above the sensor plane of the lowest point of the part that holds a
        magnet it carries, at rest: where the magnet's far face reaches at or above."""

    @abc.abstractmethod
    def travel_room(self) -> Float[Array, ""]:
        """How far (m) the source can move towards the sensors before the part bottoms out."""

    def outputs(self, displacement: Float[Array, "n 3"]) -> dict[str, Float[Array, ""]]:
        """Scalar outputs (SI) of the mechanics over a sweep's displacements (n, 3) (m):
        ``travel_fraction``, the largest travel towards the sensors over :meth:`travel_room`
        (above 1 the part would have to pass through itself)."""
        return {"travel_fraction": jnp.max(-displacement[:, 2]) / self.travel_room()}


class Dome(AbstractMechanics):
    """The dome-Hall sensor's hemispherical dome pressed at its apex by a flat plate.

    The apex moves by -C(F) F along z, C the secant compliance of
    :func:`magdesign.mechanics.dome_compliance` at that force (every force of a sweep
    found on one followed path; ``throw=False``: its result becomes the converged flag), on
    ``mesh`` (elements through the wall, along the meridian; the axisymmetric level only). A
    dome carries no modelled shear: shear loads do not move it.
    """

    outer_radius: Float[Array, ""]
    thickness: Float[Array, ""]
    material: AbstractMaterial
    fidelity: str = eqx.field(static=True)
    base: str = eqx.field(static=True)
    mesh: tuple[int, int] = eqx.field(static=True, default=DEFAULT_MESH)

    PARAMETERS: ClassVar = {
        "mechanics.outer_radius": lambda m: m.outer_radius,
        "mechanics.thickness": lambda m: m.thickness,
    }

    def compliance(self, force):
        compliance, result = mechanics.dome_compliance(
            outer_radius=self.outer_radius,
            thickness=self.thickness,
            material=self.material,
            max_force=force,
            fidelity=self.fidelity,
            base=self.base,
            mesh=self.mesh,
            throw=False,
        )
        return compliance, result == mechanics.DomeResult.successful

    output_units: ClassVar = {**AbstractMechanics.output_units, "outer_radius": "m", "wall_fraction": "1"}

    def top(self):
        """The dome's outer apex, R_o above its base plane."""
        return self.outer_radius

    def bottom(self):
        """The dome's inner apex, R_o - t above its base plane: below it lies the cavity."""
        return self.outer_radius - self.thickness

    def travel_room(self):
        """The dome's inner height R_o - t: the apex meets the base plane there."""
        return self.outer_radius - self.thickness

    def outputs(self, displacement):
        """The common outputs, the outer radius (m) and ``wall_fraction``, the wall over the
        outer radius (a dome exists below 1)."""
        return {
            **super().outputs(displacement),
            "outer_radius": self.outer_radius,
            "wall_fraction": self.thickness / self.outer_radius,
        }

    def displacement(self, loads):
        compliance, converged = self.compliance(loads.normal)
        uz = -compliance * loads.normal
        return jnp.stack([jnp.zeros_like(uz), jnp.zeros_like(uz), uz], axis=-1), converged


class Layer(AbstractMechanics):
    """A flat elastomer layer of ``thickness`` h under a contact of ``contact_area`` S.

    Displacement (Fx / k_s, Fy / k_s, -Fz / k_n) with the layer stiffness of
    :func:`magdesign.mechanics.layer_stiffness` (fidelity "hooke" or "bonded").
    """

    thickness: Float[Array, ""]
    contact_area: Float[Array, ""]
    material: AbstractMaterial
    fidelity: str = eqx.field(static=True)

    PARAMETERS: ClassVar = {
        "mechanics.thickness": lambda m: m.thickness,
        "mechanics.contact_area": lambda m: m.contact_area,
    }

    @property
    def stiffness(self):
        return mechanics.layer_stiffness(
            thickness=self.thickness, area=self.contact_area, material=self.material, fidelity=self.fidelity
        )

    def compliance(self, force):
        return 1.0 / self.stiffness.normal, jnp.asarray(True)

    def top(self):
        """The layer's top face, its thickness above the sensor plane it lies on."""
        return self.thickness

    def bottom(self):
        """The sensor plane the layer lies on: the layer is solid down to it."""
        return 0.0 * self.thickness  # numpy for a numpy layer (the spec's checks, on the host)

    def travel_room(self):
        """The layer's thickness: pressed to nothing at that travel."""
        return self.thickness

    def displacement(self, loads):
        stiffness = self.stiffness
        u = jnp.concatenate([loads.shear / stiffness.shear, -loads.normal[:, None] / stiffness.normal], axis=-1)
        return u, jnp.ones(loads.normal.shape, bool)
