"""Dome compliance (PHYSICS.md 2.3): Reissner and axisymmetric levels, bad input.

The axisymmetric references are independent of this model: seed 001's published 1.6 mm
at 5 N (Abaqus and experiment), a 4x finer mesh of the same model, central differences.
Each (base, mesh) is compiled once (``_axisymmetric``) and shared between tests.
"""

import functools

import jax
import numpy as np
import optimistix as optx
import pytest

from magdesign.mechanics import LinearElastic, MooneyRivlin, dome_compliance, dome_curve

RESIN = MooneyRivlin(c10=0.1182e6, c01=0.1769e6)


def test_reissner_equals_its_formula():
    E, nu, Ro, t = 1.771e6, 0.3, 8e-3, 2e-3
    c = dome_compliance(
        outer_radius=Ro, thickness=t, material=LinearElastic(E=E, nu=nu), max_force=5.0,
        fidelity="reissner",
    )
    R = Ro - t / 2
    assert float(c) == pytest.approx(R * np.sqrt(3 * (1 - nu**2)) / (4 * E * t**2), rel=1e-15)


def test_reissner_seed_dome_is_0_371_mm_per_newton():
    c = dome_compliance(outer_radius=8e-3, thickness=2e-3, material=RESIN, max_force=5.0,
                        fidelity="reissner")
    assert float(c) * 1e3 == pytest.approx(0.371, abs=0.0015)


def test_reissner_curve_is_linear_and_finite_at_zero_force():
    d, f = dome_curve(outer_radius=8e-3, thickness=2e-3, material=RESIN, max_force=5.0,
                      fidelity="reissner", n_points=5)
    np.testing.assert_allclose(f, [1, 2, 3, 4, 5])
    np.testing.assert_allclose(d / f, d[-1] / f[-1], rtol=1e-15)
    c0 = dome_compliance(outer_radius=8e-3, thickness=2e-3, material=RESIN, max_force=0.0,
                         fidelity="reissner")
    assert np.isfinite(float(c0))


def test_reissner_thickness_for_target_compliance_closed_form():
    # C = R s / (4 E t^2), R = Ro - t/2  ->  4 E C t^2 + (s/2) t - s Ro = 0
    Ro, target = 8e-3, 0.32e-3
    E, nu = RESIN.youngs_modulus, RESIN.poisson_ratio
    s = np.sqrt(3 * (1 - nu**2))
    a, b, cc = 4 * E * target, s / 2, s * Ro
    expected = float((-b + np.sqrt(b * b + 4 * a * cc)) / (2 * a))

    def fn(t, _):
        return dome_compliance(outer_radius=Ro, thickness=t, material=RESIN, max_force=5.0,
                               fidelity="reissner") / target - 1.0

    sol = optx.root_find(fn, optx.Newton(rtol=1e-12, atol=1e-15), 2e-3, throw=False)
    assert sol.result == optx.RESULTS.successful
    assert float(sol.value) == pytest.approx(expected, rel=1e-10)
    assert float(sol.value) * 1e3 == pytest.approx(2.14, abs=0.01)


def test_reissner_grad_and_vmap():
    def c(Ro, t, c10, c01):
        return dome_compliance(outer_radius=Ro, thickness=t,
                               material=MooneyRivlin(c10=c10, c01=c01), max_force=5.0,
                               fidelity="reissner")

    args = (8e-3, 2e-3, 0.1182e6, 0.1769e6)
    grads = jax.jit(jax.grad(c, argnums=(0, 1, 2, 3)))(*args)
    for i, g in enumerate(grads):
        h = args[i] * 1e-5
        lo, hi = list(args), list(args)
        lo[i] -= h
        hi[i] += h
        assert float(g) == pytest.approx(float(c(*hi) - c(*lo)) / (2 * h), rel=1e-6)
    ts = np.linspace(0.02, 0.5, 7) * 8e-3
    out = jax.vmap(lambda t: c(8e-3, t, 0.1182e6, 0.1769e6))(ts)
    assert np.all(np.isfinite(out)) and np.all(np.diff(out) < 0)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(outer_radius=-8e-3), "outer_radius"),
        (dict(thickness=0.0), "thickness"),
        (dict(thickness=8e-3), "thickness"),
        (dict(max_force=-1.0), "max_force"),
        (dict(fidelity="shell"), "fidelity"),
        (dict(base="glued"), "base"),
        (dict(mesh=(0, 16)), "mesh"),
    ],
)
def test_bad_input_raises_naming_the_argument(kwargs, name):
    args = dict(outer_radius=8e-3, thickness=2e-3, material=RESIN, max_force=5.0,
                fidelity="reissner")
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        dome_compliance(**args)


def test_unknown_fidelity_lists_the_valid_ones():
    with pytest.raises(ValueError, match="reissner.*axisymmetric"):
        dome_compliance(outer_radius=8e-3, thickness=2e-3, material=RESIN, max_force=5.0,
                        fidelity="abaqus")


SEED = (8e-3, 2e-3, 0.1182e6, 0.1769e6)  # outer radius, wall (m), c10, c01 (Pa)


@functools.cache
def _axisymmetric(base="bonded", mesh=(2, 16)):
    """(jitted compliance, jitted gradient wrt the first four arguments) of
    (outer_radius, thickness, c10, c01, max_force)."""

    def c(Ro, t, c10, c01, force):
        return dome_compliance(outer_radius=Ro, thickness=t, material=MooneyRivlin(c10=c10, c01=c01),
                               max_force=force, base=base, mesh=mesh)

    return jax.jit(c), jax.jit(jax.grad(c, argnums=(0, 1, 2, 3)))


def test_axisymmetric_seed_dome_meets_the_published_compliance():
    compliance, _ = _axisymmetric()
    c = float(compliance(*SEED, 5.0))
    assert 0.29e-3 <= c <= 0.35e-3  # issue 3's acceptance band around 1.6 mm / 5 N
    assert c * 5.0 * 1e3 == pytest.approx(1.70, abs=0.02)  # the model class's 1.70 mm


def test_axisymmetric_default_mesh_within_one_percent_of_4x_finer():
    coarse = float(_axisymmetric()[0](*SEED, 5.0))
    fine = float(_axisymmetric(mesh=(4, 32))[0](*SEED, 5.0))
    assert coarse == pytest.approx(fine, rel=0.01)


def test_axisymmetric_sliding_base_is_softer():
    bonded = float(_axisymmetric()[0](*SEED, 5.0))
    sliding = float(_axisymmetric(base="sliding")[0](*SEED, 5.0))
    assert sliding * 5.0 * 1e3 == pytest.approx(2.25, abs=0.05)
    assert sliding > 1.2 * bonded


def test_axisymmetric_gradients_equal_central_differences():
    compliance, grad = _axisymmetric()
    grads = grad(*SEED, 5.0)
    for i, g in enumerate(grads):
        h = SEED[i] * 1e-5
        lo, hi = list(SEED), list(SEED)
        lo[i] -= h
        hi[i] += h
        fd = (float(compliance(*hi, 5.0)) - float(compliance(*lo, 5.0))) / (2 * h)
        assert np.isfinite(float(g))
        assert float(g) == pytest.approx(fd, rel=1e-5)


def test_axisymmetric_finite_from_thin_to_thick_walls_and_at_zero_force():
    compliance, grad = _axisymmetric()
    Ro = SEED[0]
    for ratio in (0.02, 0.5):
        args = (Ro, ratio * Ro, SEED[2], SEED[3], 5.0)
        assert np.isfinite(float(compliance(*args)))
        assert np.all(np.isfinite(np.array(grad(*args))))
    zero = float(compliance(*SEED, 0.0))
    small = float(compliance(*SEED, 0.05))
    assert np.isfinite(zero) and 0.0 < zero
    assert np.all(np.isfinite(np.array(grad(*SEED, 0.0))))
    # the secant compliance grows towards zero load (contact stiffens the dome)
    assert zero > small > float(compliance(*SEED, 5.0))


def test_axisymmetric_curve_stiffens_with_contact():
    d, f = jax.jit(lambda: dome_curve(outer_radius=SEED[0], thickness=SEED[1], material=RESIN,
                                      max_force=5.0, n_points=5))()
    np.testing.assert_allclose(f, [1, 2, 3, 4, 5])
    assert np.all(np.diff(d) > 0)
    secant = f / d
    assert np.all(np.diff(secant) > 0)  # force rises faster than linearly (contact spreads)
    c5 = float(_axisymmetric()[0](*SEED, 5.0))
    assert float(d[-1]) == pytest.approx(c5 * 5.0, rel=1e-9)  # same equilibrium
