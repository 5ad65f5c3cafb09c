"""Dome compliance, Reissner level (PHYSICS.md 2.3) and bad input.

The axisymmetric level is not tested here yet: its load path does not converge for
seed 001's dome in this version (see the closing note of the work).
"""

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
