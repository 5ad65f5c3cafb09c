"""Elastic materials as strain-energy functions.

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


def excess_invariants(H) -> tuple[Float[Array, ""], Float[Array, ""], Float[Array, ""]]:
    """(Ibar1 - 3, Ibar2 - 3, J - 1) of F = I + H, from the displacement gradient H (3 x 3,
    rows of scalars or an array).

    Written without cancellation: a small strain e makes Ibar1 - 3 of order e^2, which
    I1 - 3 computed from F loses to rounding (relative error 1e-16 / e^2, 1e-8 at e = 1e-4,
    enough to stall a line search on the energy). Here every term is formed from H
    (C - I = H + H^T + H^T H, J - 1 by the expansion of det(I + H), J^(-2/3) - 1 by
    expm1 and log1p), so the error is 1e-16 / e relative. Scalar arithmetic rather than
    3 x 3 matrix products: XLA compiles its second derivatives three times faster.
    """
    n = range(3)
    D = [[H[i][j] + H[j][i] + sum(H[k][i] * H[k][j] for k in n) for j in n] for i in n]  # C - I
    tr_D = D[0][0] + D[1][1] + D[2][2]
    i1 = tr_D
    i2 = 2.0 * tr_D + 0.5 * (tr_D * tr_D - sum(D[i][j] * D[j][i] for i in n for j in n))
    tr_H = H[0][0] + H[1][1] + H[2][2]
    det_H = (
        H[0][0] * (H[1][1] * H[2][2] - H[1][2] * H[2][1])
        - H[0][1] * (H[1][0] * H[2][2] - H[1][2] * H[2][0])
        + H[0][2] * (H[1][0] * H[2][1] - H[1][1] * H[2][0])
    )
    j = tr_H + 0.5 * (tr_H * tr_H - sum(H[i][k] * H[k][i] for i in n for k in n)) + det_H
    return isochoric_excess(i1, i2, j)


def isochoric_excess(i1, i2, j):
    """(Ibar1 - 3, Ibar2 - 3, J - 1) from (I1 - 3, I2 - 3, J - 1), without cancellation
    (J^(-2/3) - 1 and J^(-4/3) - 1 by expm1 and log1p)."""
    log_J = jnp.log1p(j)
    s1, s2 = jnp.expm1(-2.0 / 3.0 * log_J), jnp.expm1(-4.0 / 3.0 * log_J)  # J^(-2/3) - 1, J^(-4/3) - 1
    return (1.0 + s1) * i1 + 3.0 * s1, (1.0 + s2) * i2 + 3.0 * s2, j


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
        check_positive(E=self.E, unit="Pa")
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


class AbstractHyperelastic(AbstractMaterial):
    """A finite-strain law of the decoupled form W = W_iso(Ibar1, Ibar2) + U(J), exact under
    large strains and rotations (the axisymmetric dome model needs one)."""

    @abc.abstractmethod
    def invariant_energy(self, i1, i2, j) -> Float[Array, ""]:
        """W (J/m^3) from the excess invariants i1 = Ibar1 - 3, i2 = Ibar2 - 3, j = J - 1
        (:func:`excess_invariants`); its isochoric part is the value at j = 0, its
        volumetric part the value at i1 = i2 = 0."""

    def strain_energy(self, F: Float[Array, "3 3"]) -> Float[Array, ""]:
        F = jnp.asarray(F)
        return self.invariant_energy(*excess_invariants(F - jnp.eye(3)))


class NeoHookean(AbstractHyperelastic):
    """Compressible neo-Hookean solid: W = mu/2 (Ibar1 - 3) + K/2 (J - 1)^2.

    ``mu`` shear modulus (Pa), ``bulk`` bulk modulus K (Pa), both small-strain. PDMS 1:15
    of the spin-valve matrix sensor (E = 750 kPa, nu = 0.49) is ``NeoHookean.from_youngs(E=750e3, nu=0.49)``.
    """

    mu: Float[ArrayLike, ""]
    bulk: Float[ArrayLike, ""]

    def __check_init__(self):
        check_positive(mu=self.mu, bulk=self.bulk, unit="Pa")

    @classmethod
    def from_youngs(cls, *, E: float, nu: float) -> "NeoHookean":
        """The neo-Hookean solid with small-strain Young's modulus E (Pa) and Poisson nu."""
        check_positive(E=E, unit="Pa")
        _check_poisson(nu)
        return cls(mu=E / (2.0 * (1.0 + nu)), bulk=E / (3.0 * (1.0 - 2.0 * nu)))

    def invariant_energy(self, i1, i2, j):
        return 0.5 * self.mu * i1 + 0.5 * self.bulk * j**2

    @property
    def shear_modulus(self):
        return self.mu

    @property
    def bulk_modulus(self):
        return self.bulk


class MooneyRivlin(AbstractHyperelastic):
    """Mooney-Rivlin solid: W = c10 (Ibar1 - 3) + c01 (Ibar2 - 3) + K/2 (J - 1)^2.

    ``c10`` > 0 and ``c01`` >= 0 (Pa); small-strain shear modulus mu = 2 (c10 + c01).
    ``bulk`` K (Pa) defaults to None, meaning K = DEFAULT_BULK_TO_SHEAR * mu = 1000 mu
    (nearly incompressible, nu = 0.4995); it is evaluated from c10 and c01 when used, so
    derivatives with respect to c10 and c01 keep the ratio. The dome-Hall sensor's resin is
    ``MooneyRivlin(c10=0.1182e6, c01=0.1769e6)``.
    """

    c10: Float[ArrayLike, ""]
    c01: Float[ArrayLike, ""]
    bulk: Float[ArrayLike, ""] | None = None

    def __check_init__(self):
        check_positive(c10=self.c10, unit="Pa")
        check_nonnegative(c01=self.c01, unit="Pa")
        if self.bulk is not None:
            check_positive(bulk=self.bulk, unit="Pa")

    def invariant_energy(self, i1, i2, j):
        return self.c10 * i1 + self.c01 * i2 + 0.5 * self.bulk_modulus * j**2

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
