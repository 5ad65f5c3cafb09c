"""Batches: many points of one problem solved in vmapped, sharded chunks, or a point per
call on a thread per core where the model runs slow loops of its own."""

import contextlib
import functools
import os
import sys
import time
from concurrent.futures import ThreadPoolExecutor

import jax
import jax.numpy as jnp
import numpy as np
from jax.experimental import multihost_utils
from jax.sharding import Mesh, NamedSharding, PartitionSpec
from tqdm import tqdm

from magdesign import _export
from magdesign._progress import stage
from magdesign._tracing import errors_as_nan, free_programs_near_mapping_limit, gc_paused, has_loops, program_cache
from magdesign.design._sqp.jet import _values
from magdesign.design._sqp.program import _compiled, _host, _structure, _unpack
from magdesign.design.problem import per_problem
from magdesign.design.report import STATUS_NAMES

# A sweep goes in at least about this many chunks where its points allow (see _in_chunks).
PROGRESS_STEPS = 16


def solve_batch(problem, y0, thetas, settings, *, chunk=None, progress=None, continuation=False):
    """Solve ``problem`` from each start y0 (points, n) for each theta (points, p): the
    flat :class:`CoreSolution` of numpy arrays and the wall time (s).

    On a CPU, a problem whose model runs loops of its own (an iterative solve, such as an
    axisymmetric dome's path: :func:`_iterative`) and whose first point takes longer than
    ``settings.sqp.point_seconds`` to solve is solved a point per call of the program that
    :func:`solve` compiles, on parallel threads (:func:`_one_by_one`). Any other goes in
    chunks of at most ``chunk`` points (default ``settings.sqp.chunk``), so that memory stays
    bounded, each chunk vmapped and split over every local device (``jax.sharding``;
    :func:`_in_chunks`). Under ``jax.distributed`` (more than one process) each process
    solves its share of the points and every process gets the whole result.
    ``progress``: True, False, or None (a bar when stderr is a terminal and the batch
    takes more than a second). ``continuation``: where the points go one at a time, start
    points from their predecessor's predicted optimum (see :func:`_one_by_one`).
    """
    began = time.perf_counter()
    count = thetas.shape[0]
    processes, index = jax.process_count(), jax.process_index()
    share = -(-count // processes)
    mine = slice(index * share, min((index + 1) * share, count))
    y0, thetas = np.asarray(y0, np.float64)[mine], np.asarray(thetas, np.float64)[mine]
    key, arrays = _structure(problem, settings)
    sqp = settings.sqp
    bar = (
        tqdm(
            total=share,
            unit="design",
            delay=1.0,
            disable=None if progress is None else not progress,
            file=sys.stderr,
            leave=False,
        )
        if index == 0
        else None
    )
    packed = None
    try:
        if len(y0) and jax.default_backend() == "cpu" and _iterative(problem):
            stage("compiling the solver for one point at a time (first call; later runs load it from the cache)")
            with errors_as_nan(), gc_paused():
                program = _compiled(key, False).lower(arrays, y0[0], thetas[0]).compile()
            first_began = time.perf_counter()
            first = np.asarray(program(arrays, y0[0], thetas[0]))
            if time.perf_counter() - first_began > sqp.point_seconds:
                packed = _one_by_one(_host(problem), program, arrays, first, y0, thetas, bar, continuation, sqp)
        if packed is None:
            packed = _in_chunks(key, arrays, y0, thetas, share, chunk or sqp.chunk, bar, sqp.batch_memory)
    finally:
        if bar is not None:
            bar.close()
    if processes > 1:
        with _stdout_to_stderr():  # gloo announces its connections on stdout (fd 1)
            packed = multihost_utils.process_allgather(_padded(packed, share), tiled=True)[:count]
    return _unpack(problem, packed), time.perf_counter() - began


@per_problem
def _iterative(problem):
    """Whether the problem's model runs while loops of its own (an iterative solve, such
    as an axisymmetric dome's path), read from one trace of its values; kept on disk by
    the problem's structure and shapes (:func:`magdesign._export.remembered`), so that a
    second run of a sweep does not trace the model again."""
    host = _host(problem)
    shapes = [jax.ShapeDtypeStruct(np.shape(a), jnp.float64) for a in (host.y0, host.theta)]
    avals = [(np.shape(leaf), str(leaf.dtype)) for leaf in host.leaves]

    def traced():
        with errors_as_nan():
            return has_loops(functools.partial(_values, problem), *shapes)

    return _export.remembered("iterative", f"{host.key!r}\n{avals}\n{[s.shape for s in shapes]}", traced)


def usable_cores():
    """The number of CPU cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def _one_by_one(host, program, arrays, first, y0, thetas, bar, continuation, sqp):
    """The packed solutions (points, width) of the points (y0, thetas), ``first`` that of
    the first point, solved a point per call of ``program`` (:func:`solve`'s, compiled)
    on a thread per usable core, fewer where their working memory together would pass
    sqp.batch_memory; ``host`` the problem's :class:`_Host`.

    Vmapped lanes run in lock-step: every loop of a batched program turns until its
    slowest lane is done, at each level of the nested loops of a dome's path solve, so a
    batch of axisymmetric designs takes about twice as long as its points solved one after
    another. A call releases the interpreter while it runs, so the threads run their points
    side by side.

    With ``continuation`` the points go in runs of sqp.chain, one run per thread at a
    time (the progress bar moves a point at a time): the first of a run starts from its
    y0, each next from the optimum that the point before predicts to first order with
    its implicit derivatives (where that point is successful and has them), and where a
    point so started is not successful it is solved again from its y0. The runs depend
    on the points' order (and, under ``jax.distributed``, on each process's share), not
    on the threads. Without, every point starts from its y0. Interrupted (Ctrl-C), the
    threads stop after the point each is solving."""
    memory = program.memory_analysis()
    per_point = None if memory is None else memory.temp_size_in_bytes
    workers = usable_cores() if not per_point else min(usable_cores(), max(1, sqp.batch_memory // per_point))
    lower, upper, scale = host.arrays[:3]
    n, p = y0.shape[1], thetas.shape[1]
    x_at, derivatives_at, status_at = (slice(*host.layout[name]) for name in ("x", "derivatives", "status"))

    def solved(i, start):
        return np.asarray(program(arrays, start, thetas[i]))

    def successful(packed):
        return packed is not None and packed[status_at][0] == STATUS_NAMES.index("successful")

    def predicted(before, i):
        """Point i's start from the solution ``before`` of point i - 1, or None."""
        change = thetas[i] - thetas[i - 1]
        moved = change != 0.0
        derivatives = before[derivatives_at].reshape(n, p)[:, moved]
        if not successful(before) or not np.all(np.isfinite(derivatives)):
            return None
        x = before[x_at] + derivatives @ change[moved]
        return np.clip((x - lower) / scale, 0.0, (upper - lower) / scale)

    def run(head):
        packed = [first if head == 0 else solved(head, y0[head])]
        advance(1)
        for i in range(head + 1, min(head + length, len(y0))):
            if stopping:  # the main thread was interrupted (Ctrl-C): its answer is not wanted
                break
            start = predicted(packed[-1], i)
            result = None if start is None else solved(i, start)
            packed.append(result if successful(result) else solved(i, y0[i]))
            advance(1)
        return packed

    def advance(points):
        if bar is not None:
            bar.update(points)

    length = sqp.chain if continuation else 1
    heads = range(0, len(y0), length)
    packed, stopping = [], []
    pool = ThreadPoolExecutor(max(1, min(workers, len(heads))))
    try:
        for results in pool.map(run, heads):
            packed += results
    except BaseException:
        stopping.append(True)  # the threads stop after their current point
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
    return np.stack(packed)


def _in_chunks(key, arrays, y0, thetas, share, chunk, bar, batch_memory):
    """The packed solutions (points, width) of the points (y0, thetas) in vmapped chunks,
    each split over every local device (see :func:`solve_batch`)."""
    devices = jax.local_devices()
    # equal chunks, each a multiple of the device count: one compiled shape, little padding
    # (a batch that fits one chunk is padded to a power of two, so that sweeps of nearby
    # sizes share one compiled program), and at least about PROGRESS_STEPS chunks where the
    # points allow, so that the progress bar moves and Ctrl-C, which takes effect between
    # chunks, stops a sweep of a few points soon (a vmapped lane's answer does not depend on
    # its chunk's size)
    wanted = -(-share // PROGRESS_STEPS)
    size = min(1 << max(wanted - 1, 0).bit_length(), chunk) if wanted <= chunk else -(-share // -(-share // chunk))
    size = -(-size // len(devices)) * len(devices)
    sharding = (
        NamedSharding(Mesh(np.array(devices), ("points",)), PartitionSpec("points")) if len(devices) > 1 else None
    )
    run, size = _batch_program(key, arrays, size, y0.shape[1], thetas.shape[1], sharding, batch_memory)
    packed = []
    for start in range(0, max(share, 1), size):
        part = [_padded(a[start : start + size], size) for a in (y0, thetas)]
        if sharding is not None:
            part = [jax.device_put(a, sharding) for a in part]
        packed.append(np.asarray(run(arrays, *part))[: max(0, min(size, y0.shape[0] - start))])
        if bar is not None:
            bar.update(packed[-1].shape[0])
    return np.concatenate(packed)


_PROGRAMS = program_cache({})  # (structure, chunk size, columns, devices) -> compiled batch program


def _batch_program(key, arrays, size, n, p, sharding, batch_memory):
    """(compiled program, chunk size) for chunks of ``size`` points, or of fewer where its
    working memory would pass ``batch_memory`` (bytes; an axisymmetric dome's solve takes
    about 100 MB per point): read from XLA's memory analysis of the compiled program."""
    devices = 1 if sharding is None else sharding.mesh.size
    while True:
        entry = (key, size, n, p, devices)
        if entry not in _PROGRAMS:
            stage(
                f"compiling the solver for batches of {size} point{'s' if size > 1 else ''} "
                "(first call; later runs load it from the cache)"
            )
            if len(_PROGRAMS) >= 64:
                _PROGRAMS.clear()
            free_programs_near_mapping_limit()
            shape = lambda columns: jax.ShapeDtypeStruct((size, columns), jnp.float64, sharding=sharding)  # noqa: E731
            with errors_as_nan(), gc_paused():
                _PROGRAMS[entry] = _compiled(key, True).lower(arrays, shape(n), shape(p)).compile()
        program = _PROGRAMS[entry]
        memory = program.memory_analysis()
        need = None if memory is None else memory.temp_size_in_bytes * devices
        if need is None or need <= batch_memory or size <= devices:
            return program, size
        size = max(devices, int(size * batch_memory / need) // devices * devices)


@contextlib.contextmanager
def _stdout_to_stderr():
    """File descriptor 1 sent to stderr for a while: for messages of C++ libraries that
    would break a reader of stdout (a JSON document)."""
    sys.stdout.flush()
    saved = os.dup(1)
    os.dup2(2, 1)
    try:
        yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)


def _padded(array, size):
    """``array`` (k, ...) cut or padded to (size, ...) by repeating its last row (a zero
    row where it is empty)."""
    if array.shape[0] >= size:
        return array[:size]
    last = array[-1:] if array.shape[0] else np.zeros((1, *array.shape[1:]), array.dtype)
    return np.concatenate([array, np.repeat(last, size - array.shape[0], axis=0)])
