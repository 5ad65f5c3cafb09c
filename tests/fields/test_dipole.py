"""magdesign.fields.dipole against magpylib's Dipole and its singular point."""

import jax
import jax.numpy as jnp
import magpylib
import numpy as np
import pytest

from magdesign.fields import dipole


def test_agrees_with_magpylib():
    rng = np.random.default_rng(0)
    points = rng.uniform(-1e-2, 1e-2, size=(500, 3))
    moment = np.array([0.02, -0.01, 0.05])
    expected = magpylib.misc.Dipole(moment=moment).getB(points)
    # magpylib takes mu0 = 4 pi 1e-7 exactly; magdesign the CODATA 2018 value (5e-10 apart)
    np.testing.assert_allclose(dipole(points, moment), expected, rtol=1e-9)


def test_origin_is_finite_with_finite_gradients():
    moment = jnp.array([0.0, 0.0, 1.0])
    assert np.all(np.asarray(dipole(jnp.zeros(3), moment)) == 0)
    assert np.all(np.isfinite(jax.jacrev(dipole)(jnp.zeros(3), moment)))


def test_bad_shapes():
    with pytest.raises(ValueError, match="points"):
        dipole(np.zeros((2, 2)), np.ones(3))
    with pytest.raises(ValueError, match="moment"):
        dipole(np.zeros(3), np.ones(2))
    with pytest.raises(ValueError, match=r"moment has shape \(4, 3\), which does not broadcast with points"):
        dipole(np.zeros((5, 3)), np.ones((4, 3)))
