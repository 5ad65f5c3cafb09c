"""Elastic materials as strain-energy functions (PHYSICS.md 2.2).

Each material is an equinox module holding its constants (Pa) and a strain-energy
density W(F) (J/m^3) of the deformation gradient F (3 x 3, dimensionless). Stresses
are never written by hand: the first Piola-Kirchhoff stress is P = dW/dF by
``jax.grad`` (:meth:`AbstractMaterial.first_piola`), the Cauchy stress
sigma = P F^T / det F.

The hyperelastic laws use the decoupled (Abaqus) form, the isochoric part written with
the modified invariants Ibar1 = J^(-2/3) I1, Ibar2 = J^(-4/3) I2 (J = det F), plus the
volumetric energy K/2 (J - 1)^2 with K the small-strain bulk modulus. On an isochoric
F (J = 1) the isochoric part is the classical incompressible energy, so eliminating the
hydrostatic pressure from P reproduces the incompressible closed forms exactly.
"""

import abc

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from magdesign._validation import check_nonnegative, check_positive

# Default bulk-to-shear ratio K / mu of MooneyRivlin: nearly incompressible, Poisson's
# ratio (3 K - 2 mu) / (2 (3 K + mu)) = 0.4995, as for cured elastomers and resins;
# large enough that the compliance of a dome is within 0.1 % of the incompressible limit,
# small enough for the stiffness matrix of the axisymmetric model to stay well conditioned.
DEFAULT_BULK_TO_SHEAR = 1000.0


def _det3(F):
    """det F of a 3 x 3 matrix by cofactors (jnp.linalg.det's LU compiles far slower)."""
    return jnp.dot(F[0], jnp.cross(F[1], F[2]))


def _isochoric_invariants(F):
    """(Ibar1, Ibar2, J) of the deformation gradient F."""
    J = _det3(F)
    C = F.T @ F
    I1 = jnp.trace(C)
    I2 = 0.5 * (I1**2 - jnp.sum(C * C))
    return J ** (-2.0 / 3.0) * I1, J ** (-4.0 / 3.0) * I2, J


class AbstractMaterial(eqx.Module):
    """An elastic material: a strain energy W(F) and its small-strain moduli."""

    @abc.abstractmethod
    def strain_energy(self, F: Float[Array, "3 3"]) -> Float[Array, ""]:
        """Strain-energy density W (J/m^3) at the deformation gradient ``F`` (3, 3)."""

    @property
    @abc.abstractmethod
    def shear_modulus(self) -> Float[ArrayLike, ""]:
        """Small-strain shear modulus mu (Pa)."""

    @property
    @abc.abstractmethod
    def bulk_modulus(self) -> Float[ArrayLike, ""]:
        """Small-strain bulk modulus K (Pa)."""

    @property
    def youngs_modulus(self) -> Float[ArrayLike, ""]:
        """Small-strain Young's modulus E = 9 K mu / (3 K + mu) (Pa)."""
        K, mu = self.bulk_modulus, self.shear_modulus
        return 9.0 * K * mu / (3.0 * K + mu)

    @property
    def poisson_ratio(self) -> Float[ArrayLike, ""]:
        """Small-strain Poisson's ratio nu = (3 K - 2 mu) / (2 (3 K + mu)) (-)."""
        K, mu = self.bulk_modulus, self.shear_modulus
        return (3.0 * K - 2.0 * mu) / (2.0 * (3.0 * K + mu))

    def first_piola(self, F: Float[Array, "3 3"]) -> Float[Array, "3 3"]:
        """First Piola-Kirchhoff stress P = dW/dF (Pa), (3, 3), by ``jax.grad``."""
        return jax.grad(self.strain_energy)(jnp.asarray(F, dtype=float))

    def cauchy_stress(self, F: Float[Array, "3 3"]) -> Float[Array, "3 3"]:
        """Cauchy (true) stress sigma = P F^T / det F (Pa), (3, 3)."""
        F = jnp.asarray(F, dtype=float)
        return self.first_piola(F) @ F.T / _det3(F)


class LinearElastic(AbstractMaterial):
    """Isotropic linear (small-strain) elasticity, Young's modulus E (Pa), Poisson nu.

    W = mu eps:eps + lambda/2 tr(eps)^2 with the infinitesimal strain
    eps = (F + F^T)/2 - I; valid for small displacement gradients only (it is not
    rotation invariant). -1 < nu < 1/2.
    """

    E: Float[ArrayLike, ""]
    nu: Float[ArrayLike, ""]

    def __check_init__(self):
        check_positive(E=self.E)
        _check_poisson(self.nu)

    def strain_energy(self, F: Float[Array, "3 3"]) -> Float[Array, ""]:
        eps = 0.5 * (F + F.T) - jnp.eye(3)
        lam = self.bulk_modulus - 2.0 / 3.0 * self.shear_modulus
        return self.shear_modulus * jnp.sum(eps * eps) + 0.5 * lam * jnp.trace(eps) ** 2

    @property
    def shear_modulus(self):
        return self.E / (2.0 * (1.0 + self.nu))

    @property
    def bulk_modulus(self):
        return self.E / (3.0 * (1.0 - 2.0 * self.nu))


class NeoHookean(AbstractMaterial):
    """Compressible neo-Hookean solid: W = mu/2 (Ibar1 - 3) + K/2 (J - 1)^2.

    ``mu`` shear modulus (Pa), ``bulk`` bulk modulus K (Pa), both small-strain. PDMS 1:15
    of seed 002 (E = 750 kPa, nu = 0.49) is ``NeoHookean.from_youngs(E=750e3, nu=0.49)``.
    """

    mu: Float[ArrayLike, ""]
    bulk: Float[ArrayLike, ""]

    def __check_init__(self):
        check_positive(mu=self.mu, bulk=self.bulk)

    @classmethod
    def from_youngs(cls, *, E: float, nu: float) -> "NeoHookean":
        """The neo-Hookean solid with small-strain Young's modulus E (Pa) and Poisson nu."""
        check_positive(E=E)
        _check_poisson(nu)
        return cls(mu=E / (2.0 * (1.0 + nu)), bulk=E / (3.0 * (1.0 - 2.0 * nu)))

    def strain_energy(self, F: Float[Array, "3 3"]) -> Float[Array, ""]:
        Ibar1, _, J = _isochoric_invariants(F)
        return 0.5 * self.mu * (Ibar1 - 3.0) + 0.5 * self.bulk * (J - 1.0) ** 2

    @property
    def shear_modulus(self):
        return self.mu

    @property
    def bulk_modulus(self):
        return self.bulk


class MooneyRivlin(AbstractMaterial):
    """Mooney-Rivlin solid: W = c10 (Ibar1 - 3) + c01 (Ibar2 - 3) + K/2 (J - 1)^2.

    ``c10`` > 0 and ``c01`` >= 0 (Pa); small-strain shear modulus mu = 2 (c10 + c01).
    ``bulk`` K (Pa) defaults to None, meaning K = DEFAULT_BULK_TO_SHEAR * mu = 1000 mu
    (nearly incompressible, nu = 0.4995); it is evaluated from c10 and c01 when used, so
    derivatives with respect to c10 and c01 keep the ratio. Seed 001's resin is
    ``MooneyRivlin(c10=0.1182e6, c01=0.1769e6)``.
    """

    c10: Float[ArrayLike, ""]
    c01: Float[ArrayLike, ""]
    bulk: Float[ArrayLike, ""] | None = None

    def __check_init__(self):
        check_positive(c10=self.c10)
        check_nonnegative(c01=self.c01)
        if self.bulk is not None:
            check_positive(bulk=self.bulk)

    def strain_energy(self, F: Float[Array, "3 3"]) -> Float[Array, ""]:
        Ibar1, Ibar2, J = _isochoric_invariants(F)
        return (
            self.c10 * (Ibar1 - 3.0)
            + self.c01 * (Ibar2 - 3.0)
            + 0.5 * self.bulk_modulus * (J - 1.0) ** 2
        )

    @property
    def shear_modulus(self):
        return 2.0 * (self.c10 + self.c01)

    @property
    def bulk_modulus(self):
        if self.bulk is None:
            return DEFAULT_BULK_TO_SHEAR * self.shear_modulus
        return self.bulk


def _check_poisson(nu):
    """ValueError naming ``nu`` unless -1 < nu < 1/2 (tracers pass)."""
    if isinstance(nu, jax.core.Tracer):
        return
    value = np.asarray(nu)
    if not np.all((value > -1.0) & (value < 0.5)):
        raise ValueError(f"nu must lie in (-1, 0.5), got {nu!r}")
