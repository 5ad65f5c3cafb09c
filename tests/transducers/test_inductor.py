import jax
import jax.numpy as jnp
import numpy as np
import pytest

from magdesign.transducers import count_events, emf, slip_flags

DT = 1e-3  # the GMR-inductor paper samples every 1 ms (Fig. 13)


def test_emf_of_linear_flux_is_exact():
    t = np.arange(50) * DT
    flux = np.stack([2e-6 * t, -3e-6 * t + 1e-7], axis=-1)
    np.testing.assert_allclose(emf(flux, dt=DT, turns=40), np.broadcast_to([-8e-5, 1.2e-4], (50, 2)), rtol=1e-10)


def test_emf_of_sinusoid_matches_faraday():
    omega, phi0, turns = 2 * np.pi * 5.0, 1e-6, 25
    t = np.arange(2000) * DT
    got = emf(phi0 * np.sin(omega * t), dt=DT, turns=turns)
    expected = -turns * phi0 * omega * np.cos(omega * t)
    # central difference inside: its leading error is (omega dt)^2 / 6 of the amplitude
    error = np.max(np.abs(got[1:-1] - expected[1:-1])) / (turns * phi0 * omega)
    np.testing.assert_allclose(error, (omega * DT) ** 2 / 6, rtol=1e-3)


def _stick_slip_flux(slip_sizes, n_steps=3000, channels=4, seed=1):
    """Four coils' flux under a sawtooth shear: slow build-up (stick), snap back in 2 ms (slip)."""
    rng = np.random.default_rng(seed)
    slip_at = np.linspace(0, n_steps, len(slip_sizes) + 2)[1:-1].astype(int)
    shear = np.zeros(n_steps)
    start = 0
    for at, size in zip(slip_at, slip_sizes):
        shear[start:at] = np.linspace(0.0, size, at - start)
        shear[at] = size / 2  # halfway back one sample later
        start = at + 1
    shear[start:] = np.linspace(0.0, 0.2, n_steps - start)
    coupling = np.array([1.0, -0.8, 0.6, -1.2]) * 1e-5  # Wb per unit shear, per coil
    flux = shear[:, None] * coupling[None, :channels]
    return flux + 2e-10 * rng.standard_normal(flux.shape), slip_at


def test_three_slips_flagged_exactly_three_times():
    flux, slip_at = _stick_slip_flux([1.0, 0.6, 0.1])  # the third slip is small, as in the GMR-inductor paper's Fig. 13
    output = emf(flux, dt=DT, turns=10)
    flags = slip_flags(output, window=100)
    assert int(count_events(flags)) == 3
    flagged = np.flatnonzero(np.asarray(flags))
    assert all(np.min(np.abs(flagged - at)) <= 2 for at in slip_at)
    assert np.all(np.min(np.abs(flagged[:, None] - slip_at[None, :]), axis=1) <= 2)
    # a single channel alone raises false alarms on its noise; requiring all four rejects them
    single = jax.vmap(lambda channel: count_events(slip_flags(channel, window=100)), in_axes=1)(output)
    assert int(jnp.max(single)) > 3


def test_no_slip_no_flag_and_jit_equals_eager():
    flux, _ = _stick_slip_flux([])
    output = emf(flux, dt=DT)
    assert int(count_events(slip_flags(output, window=100))) == 0
    flux, _ = _stick_slip_flux([1.0, 0.6, 0.1])
    output = emf(flux, dt=DT)
    eager = slip_flags(output, window=100)
    jitted = jax.jit(slip_flags, static_argnames=("window", "n_sigma"))(output, window=100)
    np.testing.assert_array_equal(eager, jitted)


def test_count_events():
    np.testing.assert_equal(int(count_events(jnp.array([1, 1, 0, 1, 0, 0, 1, 1], dtype=bool))), 3)
    np.testing.assert_equal(int(count_events(jnp.zeros(5, dtype=bool))), 0)


def test_emf_grad_and_vmap():
    t = jnp.arange(20) * DT
    grad = jax.grad(lambda a: jnp.sum(emf(a * jnp.sin(30 * t), dt=DT)))(1e-6)
    assert np.isfinite(grad)
    batched = jax.vmap(lambda a: emf(a * t, dt=DT))(jnp.array([1.0, 2.0]))
    np.testing.assert_allclose(batched[:, 0], [-1.0, -2.0], rtol=1e-10)


def test_bad_input():
    with pytest.raises(ValueError, match="window"):
        slip_flags(jnp.zeros((10, 4)), window=1)
    with pytest.raises(ValueError, match="flux"):
        emf(jnp.zeros(1), dt=DT)
