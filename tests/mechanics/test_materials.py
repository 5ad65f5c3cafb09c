"""Materials: stresses from jax.grad of the energy against closed forms.

The incompressible closed forms are compared with the full (nearly incompressible)
energy evaluated at an isochoric F (det F = 1) with the hydrostatic pressure eliminated
through a traction-free lateral face: the volumetric and the J^(-2/3) parts of the
energy only add a pressure, which the elimination removes, so the match is exact.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from magdesign.mechanics import LinearElastic, MooneyRivlin, NeoHookean

C10, C01 = 0.1182e6, 0.1769e6
STRETCHES = np.linspace(0.5, 3.0, 24)  # avoids lambda = 1, where the stresses vanish
RTOL = 1e-12

MATERIALS = {
    "mooney_rivlin": (MooneyRivlin(c10=C10, c01=C01), C10, C01),
    "neo_hookean": (NeoHookean(mu=2 * C10, bulk=5e8), C10, 0.0),
}


def _piola_batch(material, Fs):
    return jax.jit(jax.vmap(material.first_piola))(jnp.asarray(Fs))


@pytest.mark.parametrize("name", MATERIALS)
def test_uniaxial_nominal_stress(name):
    material, c10, c01 = MATERIALS[name]
    lam = STRETCHES
    Fs = np.zeros((lam.size, 3, 3))
    Fs[:, 0, 0], Fs[:, 1, 1], Fs[:, 2, 2] = lam, lam**-0.5, lam**-0.5
    P = _piola_batch(material, Fs)
    # traction-free sides: P22 = dW/dF22 - p / F22 = 0 fixes p; then P11 = dW/dF11 - p / F11
    nominal = P[:, 0, 0] - P[:, 1, 1] * Fs[:, 1, 1] / Fs[:, 0, 0]
    expected = 2.0 * (lam - lam**-2) * (c10 + c01 / lam)
    np.testing.assert_allclose(nominal, expected, rtol=RTOL)
    # the two lateral faces carry the same stress by symmetry
    np.testing.assert_allclose(P[:, 1, 1], P[:, 2, 2], rtol=RTOL)


@pytest.mark.parametrize("name", MATERIALS)
def test_equibiaxial_nominal_stress(name):
    material, c10, c01 = MATERIALS[name]
    lam = STRETCHES
    Fs = np.zeros((lam.size, 3, 3))
    Fs[:, 0, 0], Fs[:, 1, 1], Fs[:, 2, 2] = lam, lam, lam**-2
    P = _piola_batch(material, Fs)
    nominal = P[:, 0, 0] - P[:, 2, 2] * Fs[:, 2, 2] / Fs[:, 0, 0]
    expected = 2.0 * (lam - lam**-5) * (c10 + c01 * lam**2)
    np.testing.assert_allclose(nominal, expected, rtol=RTOL)


@pytest.mark.parametrize("name", MATERIALS)
def test_simple_shear_cauchy_stress(name):
    material, c10, c01 = MATERIALS[name]
    gammas = STRETCHES  # amounts of shear 0.5..3
    Fs = np.tile(np.eye(3), (gammas.size, 1, 1))
    Fs[:, 0, 1] = gammas
    sigma = jax.vmap(material.cauchy_stress)(jnp.asarray(Fs))
    # incompressible Mooney-Rivlin: sigma = -p I + 2 c10 B - 2 c01 B^-1
    np.testing.assert_allclose(sigma[:, 0, 1], 2.0 * (c10 + c01) * gammas, rtol=RTOL)
    np.testing.assert_allclose(sigma[:, 0, 0] - sigma[:, 2, 2], 2.0 * c10 * gammas**2, rtol=RTOL)
    if c01 > 0:
        np.testing.assert_allclose(sigma[:, 1, 1] - sigma[:, 2, 2], -2.0 * c01 * gammas**2, rtol=RTOL)


def test_small_strain_moduli():
    mr = MooneyRivlin(c10=C10, c01=C01)
    mu = 2 * (C10 + C01)
    assert mr.shear_modulus == pytest.approx(mu, rel=1e-15)
    assert mr.bulk_modulus == pytest.approx(1000 * mu, rel=1e-15)
    # E -> 3 mu in the incompressible limit (1.771 MPa for the dome-Hall paper's resin)
    assert mr.youngs_modulus == pytest.approx(3 * mu, rel=1e-3)
    assert MooneyRivlin(c10=C10, c01=C01, bulk=1e15).youngs_modulus == pytest.approx(3 * mu, rel=1e-9)
    pdms = NeoHookean.from_youngs(E=750e3, nu=0.49)
    assert pdms.youngs_modulus == pytest.approx(750e3, rel=1e-13)
    assert pdms.poisson_ratio == pytest.approx(0.49, rel=1e-13)
    assert pdms.shear_modulus == pytest.approx(750e3 / 2.98, rel=1e-13)


@pytest.mark.slow
def test_hyperelastic_small_strain_limit_matches_bulk_and_shear():
    # the tangent of the energy at F = I gives back the stated small-strain moduli
    for material in (MooneyRivlin(c10=C10, c01=C01, bulk=3e6), NeoHookean(mu=4e5, bulk=2e7)):
        tangent = jax.jacfwd(material.first_piola)(jnp.eye(3))
        mu, K = material.shear_modulus, material.bulk_modulus
        # linear tangent C_ijkl = (K - 2 mu / 3) d_ij d_kl + mu (d_ik d_jl + d_il d_jk)
        assert float(tangent[0, 1, 0, 1]) == pytest.approx(mu, rel=1e-12)
        assert float(tangent[0, 1, 1, 0]) == pytest.approx(mu, rel=1e-12)
        hydro = sum(float(tangent[i, i, j, j]) for i in range(3) for j in range(3)) / 9.0
        assert hydro == pytest.approx(K, rel=1e-12)


def test_linear_elastic_uniaxial_hooke():
    E, nu, e = 2.3e6, 0.3, 1e-3
    material = LinearElastic(E=E, nu=nu)
    F = jnp.diag(jnp.array([1 + e, 1 - nu * e, 1 - nu * e]))
    P = material.first_piola(F)
    np.testing.assert_allclose(P[0, 0], E * e, rtol=1e-12)
    np.testing.assert_allclose(P[1, 1], 0.0, atol=1e-12 * E * e)
    assert material.youngs_modulus == pytest.approx(E, rel=1e-14)
    assert material.poisson_ratio == pytest.approx(nu, rel=1e-14)


def test_grad_with_respect_to_constants_is_finite_and_right():
    # d(uniaxial nominal stress)/d c01 = 2 (lambda - lambda^-2) / lambda, at lambda = 3
    lam = 3.0
    F = jnp.diag(jnp.array([lam, lam**-0.5, lam**-0.5]))

    def nominal(c01):
        P = MooneyRivlin(c10=C10, c01=c01).first_piola(F)
        return P[0, 0] - P[1, 1] * F[1, 1] / F[0, 0]

    g = jax.jit(jax.grad(nominal))(C01)
    assert g == pytest.approx(2 * (lam - lam**-2) / lam, rel=1e-9)
    assert np.all(np.isfinite(jax.grad(lambda c: MooneyRivlin(c10=c, c01=C01).strain_energy(jnp.eye(3)))(C10)))


@pytest.mark.parametrize(
    "make, name",
    [
        (lambda: MooneyRivlin(c10=0.0, c01=C01), "c10"),
        (lambda: MooneyRivlin(c10=C10, c01=-1.0), "c01"),
        (lambda: MooneyRivlin(c10=C10, c01=C01, bulk=-1.0), "bulk"),
        (lambda: NeoHookean(mu=-1.0, bulk=1e6), "mu"),
        (lambda: NeoHookean(mu=1e5, bulk=0.0), "bulk"),
        (lambda: LinearElastic(E=0.0, nu=0.3), "E"),
        (lambda: LinearElastic(E=1e6, nu=0.5), "nu"),
        (lambda: NeoHookean.from_youngs(E=1e6, nu=-1.0), "nu"),
    ],
)
def test_bad_constants_raise_naming_the_argument(make, name):
    with pytest.raises(ValueError, match=rf"\b{name}\b"):
        make()


@pytest.mark.parametrize("gamma", [1e-7, 1e-4, 0.3])
def test_energy_keeps_full_precision_at_tiny_strains(gamma):
    """Simple shear is isochoric with Ibar1 - 3 = Ibar2 - 3 = gamma^2 exactly: the energy
    c10 gamma^2 + c01 gamma^2 must keep its digits where Ibar1 - 3 formed from I1 would
    lose them (relative error 1e-16 / gamma^2, 1e-2 at gamma = 1e-7)."""
    material = MooneyRivlin(c10=0.1182e6, c01=0.1769e6, bulk=1e9)
    F = jnp.eye(3).at[0, 1].set(gamma)
    expected = (0.1182e6 + 0.1769e6) * gamma**2
    assert float(material.strain_energy(F)) == pytest.approx(expected, rel=1e-9)
