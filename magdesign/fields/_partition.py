"""Evaluating a field's kernels over many points by zone: the far series everywhere, the
near kernel on the near points alone, gathered in chunks (:func:`_partitioned`), and
results computed once into memory (:func:`_materialized`). Used by the cylinder's field."""

import jax
import jax.numpy as jnp

from magdesign.fields._special import materialize

# The zones of a call's points: all near (inside the switch sphere), all far, or mixed.
NEAR, FAR, MIXED = 0, 1, 2

# Points per chunk of the near points of a partitioned call; calls of at least two chunks
# are partitioned (see _partitioned; also _derived's series), unless more than MOSTLY_NEAR
# of their points are near. On 2 cores, from 1e4 to 1e6 points with 4 % to 100 % of them
# near, chunks of 1024 to 16384 points run alike at 1e5 and 1e6 points and 2048 or less
# run faster at 1e4 (benchmarks/fields.py); above 3/4 near, both kernels elementwise beat
# the near points in chunks.
PARTITION_CHUNK = 2048
MOSTLY_NEAR = 3 / 4


def _is_large(s):
    return s.size >= 2 * PARTITION_CHUNK


def _partitioned(s, z, far, zoned):
    """``zoned(s, z, far, zone)`` at every point, each point's value from its own zone.

    Elementwise code computes both zones at every point and selects. Here, unless more
    than MOSTLY_NEAR of the points are near (in a box of +-10 radii about the dome-Hall
    sensor's magnet 4 % are), the far series (the cheap kernel) run elementwise over every point;
    then the near points alone, gathered in chunks of PARTITION_CHUNK (their indices in
    order, from one cumulative sum), go through the elliptic integrals and are written
    over their far values. Why this shape, measured at 1e6 points on 2 cores: XLA on CPU
    splits a large elementwise loop over the cores only outside loops (in a loop the far
    series ran at half their speed; the paired near kernel, a complex loop, runs on one
    core anywhere), and each full-size array (sorted copies, chunked outputs, a final
    select) cost 1-3 ms. The loop visits every chunk's place and skips those beyond the
    near points (a fixed trip count, which reverse-mode derivatives of the field's own
    derivatives need; at 1e6 points its 489 visits, most of them skipped, cost about 3
    ms). A call with more near points computes both kernels elementwise and selects.
    Under a vmap whose lanes differ in their near count, both branches run.
    """
    shape, n = s.shape, s.size
    s, z, far = s.reshape(-1), z.reshape(-1), far.reshape(-1)
    near_count = n - jnp.sum(far, dtype=jnp.int32)

    def chunk(i, arrays):
        near_index, values = arrays
        index = jax.lax.dynamic_slice(near_index, (i * PARTITION_CHUNK,), (PARTITION_CHUNK,))
        s_c, z_c = (a.at[index].get(mode="clip") for a in (s, z))  # padding: the last point, dropped below
        near_values = zoned(s_c, z_c, None, NEAR)
        return near_index, {
            name: values[name]
            .at[index]
            .set(near_values[name], mode="drop", unique_indices=True, indices_are_sorted=True)
            for name in values
        }

    def mostly_far():
        near = (~far).astype(jnp.int32)
        # The near points' indices in order, then padding past the last point. Every index
        # unique (far points go out of bounds, each to its own place, and are dropped): a
        # scatter with unique indices has a cheap derivative (second derivatives of the
        # field pass through this one).
        slots = -(-n // PARTITION_CHUNK) * PARTITION_CHUNK
        index = jnp.arange(n, dtype=jnp.int32)
        near_index = (
            (n + jnp.arange(slots, dtype=jnp.int32))
            .at[jnp.where(far, slots + index, jnp.cumsum(near) - near)]
            .set(index, mode="drop", unique_indices=True)
        )
        filled = lambda i, arrays: jax.lax.cond(i * PARTITION_CHUNK < near_count, chunk, lambda i, a: a, i, arrays)  # noqa: E731
        return jax.lax.fori_loop(0, slots // PARTITION_CHUNK, filled, (near_index, zoned(s, z, None, FAR)))[1]

    values = jax.lax.cond(near_count > MOSTLY_NEAR * n, lambda: zoned(s, z, far, MIXED), mostly_far)
    return {name: value.reshape(shape) for name, value in values.items()}


def _materialized(values, s, paired=True):
    """The named arrays, each computed once into memory
    (:func:`magdesign.fields._special.materialize`): packed two by two into complex arrays
    where ``paired`` (results that share expensive work), else each alone, as an odd one
    out is, in a real loop."""
    names = list(values)
    packed = 2 * (len(names) // 2) if paired else 0
    out = {}
    for a, b in zip(names[0:packed:2], names[1:packed:2]):
        pair = materialize(values[a], values[b], 1.0 + s)
        out.update({a: jnp.real(pair), b: jnp.imag(pair)})
    for name in names[packed:]:
        out[name] = materialize(values[name], None, 1.0 + s)
    return out
