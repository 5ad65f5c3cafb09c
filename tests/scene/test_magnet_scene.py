"""Cylinder-magnet scenes: the dome-Hall sensor against closed forms, the spin-valve
matrix's in-plane range, the GMR-inductor sensor's slip flags."""

import jax
import magpylib as magpy
import numpy as np
import pytest
from scene_helpers import example

from magdesign.fields import cylinder_axial
from magdesign.scene import Loads, loads_from_spec, outputs, scene_from_spec, simulate
from magdesign.transducers import count_events


@pytest.mark.slow
def test_inductors_flag_each_slip():
    # three stick-slip cycles at 1 kHz: the shear force ramps up for 0.2 s, then
    # snaps back within one sample; a constant 5 N presses throughout
    steps, period = 600, 200
    t = np.arange(steps) * 1e-3
    shear = 1.5 * (np.arange(steps) % period) / period
    loads = Loads(np.full(steps, 5.0), shear=np.stack([shear, np.zeros(steps)], -1), time=t)
    result = simulate(scene_from_spec(example("gmr_inductor")), loads, key=jax.random.key(0))
    flags = np.asarray(result.extras["slip"])
    slips = np.flatnonzero(np.diff(shear) < 0) + 1
    assert int(count_events(flags)) == len(slips) == 2
    for slip in slips:
        assert flags[slip - 1 : slip + 2].any()


@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.slow
def test_stick_phases_after_a_pause_are_not_slips(seed):
    """Four slips, each stick phase starting after a pause: with the inductors' own noise
    (the spec's 1.4 mV) the 3-sigma band has a width, so only the four snaps are flagged.
    Noiseless, a constant history's band has zero width and the start of every stick
    phase (and rounding) is flagged too: 9 events, found by the GMR-inductor study."""
    t = np.arange(1000) * 1e-3
    shear = np.zeros_like(t)
    starts = (0.05, 0.282, 0.514, 0.746)
    for start in starts:  # 0.2 s ramp to 0.3 N, released in 2 ms, then a pause
        shear += np.interp(t, [start, start + 0.2, start + 0.202], [0.0, 0.3, 0.0], left=0.0, right=0.0)
    loads = Loads(np.full(t.size, 5.0), shear=np.stack([shear, 0 * t], -1), time=t)
    scene = scene_from_spec(example("gmr_inductor"))
    flags = np.asarray(simulate(scene, loads, key=jax.random.key(seed)).extras["slip"])
    assert int(count_events(flags)) == len(starts)
    for start in starts:
        release = int(round((start + 0.2) * 1e3))
        assert flags[release : release + 3].any()
    noiseless = simulate(scene, loads, key=jax.random.key(seed), without=("noise",)).extras["slip"]
    assert int(count_events(noiseless)) > len(starts)


def test_dome_hall_outputs_match_closed_forms():
    spec = example("dome_hall")
    out = jax.jit(outputs)(scene_from_spec(spec, fidelity="reissner"), loads_from_spec(spec))
    # Reissner: K = 4 E t^2 / (R sqrt(3 (1 - nu^2))), R the mid-surface radius 7 mm,
    # incompressible (nu = 1/2) Mooney-Rivlin E = 6 (c10 + c01); the material's finite
    # bulk modulus (nu = 0.4995) moves it by 7e-4
    youngs, t, radius, force = 6 * (0.1182e6 + 0.1769e6), 2e-3, 7e-3, 5.0
    compliance = radius * np.sqrt(3 * (1 - 0.25)) / (4 * youngs * t**2)
    assert np.isclose(out["compliance"], compliance, rtol=1e-3)
    assert np.isclose(out["compliance"], 0.371e-3, rtol=2e-3)  # Reissner at the mid-surface radius 7 mm: 0.37 mm/N
    closest = 7.4e-3 - out["compliance"] * force
    assert np.isclose(out["closest_gap"], closest, rtol=1e-12)

    # the sensor is on the axis a gap z below the bottom face; Bz is even about the magnet's centre
    def on_axis(z):
        return cylinder_axial(z + 0.5e-3, radius=1.5e-3, height=1e-3, polarization=1.17)

    assert np.isclose(out["field_rest"], on_axis(7.4e-3), rtol=1e-10)
    assert np.isclose(out["field_closest"], on_axis(closest), rtol=1e-10)
    assert np.isclose(out["sensitivity"], (on_axis(closest) - on_axis(7.4e-3)) / force, rtol=1e-9)


def test_spin_valve_matrix_in_plane_field_range():
    spec = example("spin_valve_matrix")
    out = jax.jit(outputs)(scene_from_spec(spec), loads_from_spec(spec))
    assert np.isclose(out["compliance"] * 2.143, 0.5e-3, rtol=1e-3)  # the example's 0..0.5 mm press
    # magpylib: the 1 x 1 mm magnet 3.5 mm above a 2 x 4 grid at 2 mm pitch, pressed 0..0.5 mm;
    # the chips' sensitive axis is x. The paper's simulation gives about -0.7..+0.7 mT on
    # curved, tilted chips; this flat model gives about -1.04..+1.04 mT.
    # The example averages over each chip's 200 x 95 um active area (3 x 3 Gauss-Legendre nodes).
    x, y = np.meshgrid([-3e-3, -1e-3, 1e-3, 3e-3], [-1e-3, 1e-3])
    chips = np.stack([x.ravel(), y.ravel(), np.zeros(8)], axis=-1)
    nodes, weights = np.polynomial.legendre.leggauss(3)
    offsets = np.array([[100e-6 * u, 47.5e-6 * v, 0.0] for u in nodes for v in nodes])
    weights = np.outer(weights, weights).ravel() / 4
    bx = [
        weights
        @ magpy.magnet.Cylinder(polarization=(0, 0, 1.2), dimension=(1e-3, 1e-3), position=(0, 0, 4e-3 - press))
        .getB(chips[:, None, :] + offsets)[..., 0]
        .T
        for press in np.linspace(0.0, 3.5e-3 - float(out["closest_gap"]), 11)
    ]
    assert np.isclose(out["inplane_field_max"], np.max(np.abs(bx)), rtol=1e-9)
    assert np.isclose(out["inplane_field_min"], np.min(bx), rtol=1e-9)
    assert 0.9e-3 < out["inplane_field_max"] < 1.2e-3
