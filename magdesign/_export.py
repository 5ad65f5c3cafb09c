"""Programs kept on disk as ``jax.export`` artefacts, so that a new process skips tracing.

JAX's persistent compilation cache keeps compiled executables, but a new process must
still trace and lower a program to find its cache key, which for the design solver takes
longer than the solve. Here a program of one structure is exported once (StableHLO, with
every array argument an argument of the program: the spec's numbers are never constants
in it), serialized beside the compilation cache and deserialized by later processes; the
compilation cache then holds the executable of the deserialized program. Beside it each
compiled executable is kept too, one per concrete shapes of the arguments (see
:class:`_Program`): a later process loads and calls it with no trace, no lowering and no
compilation-cache key to hash, and falls back to the exported program where it cannot.
A command names its run (:func:`load_ahead`): the executables that the last run of that
name read are loaded ahead in threads of their own, side by side, as the run starts.

An entry is keyed by a text that names everything the trace depends on besides its
arguments' shapes and dtypes (the caller's ``structure``: the problem's tree structure,
with its static fields), by those shapes and dtypes, and by the versions of jax, jaxlib and
magdesign (with a digest of its source files' names, sizes and times, so that an edited
checkout does not reuse a stale program). The folder is named by the CPU (see
``magdesign._cache.cache_directory``).
A structure whose text holds an object's address ("at 0x...", which differs from process
to process and so names no structure) is not kept. An entry that cannot be read, was
written by other versions or for another structure is ignored and written again. Where
exporting fails (a program with a host callback), the program is traced and jitted as
usual.

Off unless :func:`enable` names a folder (the command does for its run, see
``magdesign._cache.export_directory``); MAGDESIGN_NO_EXPORT=1 keeps it off.
MAGDESIGN_NO_RECOMPILE=1 keeps an executable that JAX read from its compilation cache as it
is, unkept, instead of compiling it once more to keep it (see :meth:`_Program._keep`): the
test suite's choice, whose every edit of magdesign is an "upgrade".
"""

import functools
import hashlib
import importlib.machinery
import importlib.util
import os
import pickle
import re
import sys
import tempfile
import threading
import types
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import jaxlib
import numpy as np
from jax.experimental import serialize_executable
from jax.experimental.compilation_cache import compilation_cache

import magdesign
from magdesign import _tracing

# The layout of an entry; a change makes every older entry a miss.
ENTRY_FORMAT = 3
_state = {"directory": None, "recompile": True}
_ADDRESS = re.compile(r" at 0x[0-9a-fA-F]+")


def enable(directory):
    """Keep exported programs in ``directory`` (a path; None: off). MAGDESIGN_NO_EXPORT set
    to anything but "" or "0" keeps it off, and so does a Python without the flatbuffers
    package; MAGDESIGN_NO_RECOMPILE so set keeps no executable read from JAX's compilation
    cache (see the module's docstring)."""
    if os.environ.get("MAGDESIGN_NO_EXPORT", "") not in ("", "0") or importlib.util.find_spec("flatbuffers") is None:
        directory = None  # turned off, or no flatbuffers, which jax.export's serialization needs
    _state["directory"] = None if directory is None else Path(directory)
    _state["recompile"] = os.environ.get("MAGDESIGN_NO_RECOMPILE", "") in ("", "0")


def directory():
    """The folder of the exported programs, or None when they are off."""
    return _state["directory"]


@functools.cache
def versions() -> str:
    """The versions an entry is valid for: jax, jaxlib, magdesign with a digest of its
    source files' names, sizes and modification times (an edit makes new entries; so does
    a fresh copy of the same files), and the entry format."""
    package = Path(__file__).parent
    digest = hashlib.sha256()
    for path in sorted(package.rglob("*.py")):
        stat = path.stat()
        digest.update(f"{path.relative_to(package)} {stat.st_size} {stat.st_mtime_ns}\n".encode())
    return (
        f"jax {jax.__version__}, jaxlib {jaxlib.__version__}, "
        f"magdesign {magdesign.__version__} {digest.hexdigest()[:16]}, format {ENTRY_FORMAT}"
    )


def jit(fn, name: str, structure: str, *, compiler_options=None, batched=()):
    """``jax.jit(fn)`` for a ``fn`` of arrays (pytrees of arrays in, pytree of arrays
    out) whose trace depends on nothing but ``structure`` (a text) and its arguments'
    shapes and dtypes: the trace of each set of shapes is read from the kept entry where
    there is one, else made and kept (see the module's docstring).

    Args:
        fn: the function.
        name: a short name for the entry's file ("solve", "outputs").
        structure: a text naming everything else that ``fn``'s trace depends on.
        compiler_options: XLA options of the compiled program (as ``jax.jit``'s), or a
            function without arguments that returns them, asked only when the program is
            first traced (a kept executable needs no options); such a function keys the
            entries by its name, so its answer must depend on nothing but the versions.
        batched: the positions of the arguments whose leading axis is a batch: an entry
            is kept for any length of it (shape polymorphism), where export allows.

    Returns:
        The jitted function (``lower`` and ``compile`` as ``jax.jit``'s), whose compiled
        executables are kept too (:class:`_Program`).
    """

    def body(*args):
        leaves, in_tree = jax.tree.flatten(args)
        first = {id(leaf) for i in batched for leaf in jax.tree.leaves(args[i])}
        # the error mode is read when traced (magdesign._tracing.checked)
        traced = f"{structure}\nerrors as NaN: {_tracing._errors['as_nan']}"
        kept = _kept(fn, name, traced, in_tree, tuple(_aval(leaf, id(leaf) in first) for leaf in leaves))
        if kept is None or kept is _UNEXPORTABLE:
            return fn(*args)
        exported, out_tree = kept
        return jax.tree.unflatten(out_tree, exported.call(*leaves))

    body.__name__ = body.__qualname__ = getattr(fn, "__name__", "body")  # the compiled program's name
    options = compiler_options or {}
    named = f"{options.__module__}.{options.__qualname__}()" if callable(options) else sorted(options.items())
    return _Program(body, options, f"{name}\n{structure}\n{named}")


# (folder, program text, error mode, in_tree, avals) -> ((path, entry text), Compiled or None)
_LOADED = _tracing.program_cache({})
_CACHE_HITS = [0]  # how many programs JAX has read from its compilation cache


def _count_cache_hit(event, **kwargs):
    if event == "/jax/compilation_cache/cache_hits":
        _CACHE_HITS[0] += 1


jax.monitoring.register_event_listener(_count_cache_hit)


class _Program:
    """A ``jax.jit`` function whose compiled executables are kept on disk too, one per
    structure and concrete shapes of the arguments (a batch's length included), so that
    a later process calls its program without tracing, lowering or hashing it for the
    compilation cache. An entry's text (``program``: the name, structure and compiler
    options, then the error mode, the arguments' tree, shapes, dtypes and weak types, the
    backend, device kind, XLA_FLAGS and :func:`versions`) keys it as :func:`_kept`'s does;
    one that is missing, damaged, for another text or fails to load is compiled the
    usual way (through the exported program and the compilation cache) and kept again;
    where JAX read it from its compilation cache, it is compiled once more to be kept
    (see :meth:`_keep`).
    An executable with host callbacks is never kept. Off where :func:`directory` is, on
    several devices and inside another program's trace."""

    def __init__(self, body, options, program):
        self._body, self._options, self._program = body, options, program

    @functools.cached_property
    def _compiler_options(self):
        return self._options() if callable(self._options) else self._options

    @functools.cached_property
    def _jitted(self):
        return jax.jit(self._body, compiler_options=self._compiler_options)

    def __getattr__(self, name):  # trace, eval_shape, ... as jax.jit's
        return getattr(self._jitted, name)

    def __call__(self, *args):
        place, compiled = self._executable(args)
        if place is None:
            return self._jitted(*args)
        if compiled is None:
            compiled = self._keep(place, args, self._jitted.lower(*args).compile)
        return compiled(*args)

    def lower(self, *args):
        """``jax.jit``'s ``lower``, or only its ``compile`` where a kept executable answers."""
        place, compiled = self._executable(args)
        if compiled is not None:
            return types.SimpleNamespace(compile=lambda: compiled)
        lowered = self._jitted.lower(*args)
        if place is None:
            return lowered
        return types.SimpleNamespace(compile=lambda: self._keep(place, args, lowered.compile))

    def _executable(self, args):
        """(place, the kept executable or None) for ``args`` (arrays or ShapeDtypeStructs);
        place None where executables are not kept."""
        folder = directory()
        leaves, in_tree = jax.tree.flatten((args, {}))
        if folder is None or jax.device_count() > 1 or any(isinstance(leaf, jax.core.Tracer) for leaf in leaves):
            return None, None
        avals = tuple((tuple(leaf.shape), str(leaf.dtype), bool(getattr(leaf, "weak_type", False))) for leaf in leaves)
        memo = (folder, self._program, _tracing._errors["as_nan"], in_tree, avals)
        if memo not in _LOADED:
            if _ADDRESS.search(self._program) or _ADDRESS.search(str(in_tree)):
                return None, None  # no stable text
            device = jax.devices()[0]
            text = (
                f"{self._program}\nerrors as NaN: {memo[2]}\n{in_tree}\n{avals}\n"
                f"{device.client.platform} {device.client.platform_version} {device.device_kind}\n"
                f"XLA_FLAGS={os.environ.get('XLA_FLAGS', '')}\n{versions()}"
            )
            name = self._program.split("\n", 1)[0]
            path = folder / f"{name}-{hashlib.sha256(text.encode()).hexdigest()[:32]}.executable"
            if len(_LOADED) >= 64:
                _LOADED.clear()
            _LOADED[memo] = (path, text), _read_executable(path, text, in_tree)
        place, compiled = _LOADED[memo]
        if _USED is not None and place[0] not in _USED:
            _USED.append(place[0])  # for the next run's load_ahead, loaded here or compiled and kept
        return (memo, *place), compiled

    def _keep(self, place, args, compile):
        """The jax.stages.Compiled that ``compile()`` returns for ``args``, kept in memory and
        written to its entry. An executable that JAX read from its persistent compilation
        cache serializes without its kernels (its entry would fail when run), and a cache
        that holds the program while the entry is missing is what every run meets after
        an upgrade of magdesign (new :func:`versions`, the same program): such a program is
        compiled once more with the cache bypassed (:meth:`_compiled_afresh`), and that
        executable is kept and returned; with MAGDESIGN_NO_RECOMPILE (see :func:`enable`),
        the executable read from the cache is returned and nothing is kept."""
        memo, path, text = place
        hits = _CACHE_HITS[0]
        compiled = compile()
        fresh = _CACHE_HITS[0] == hits
        if not fresh and _state["recompile"]:
            try:
                compiled, fresh = self._compiled_afresh(args, memo[2]), True
            except Exception:  # the executable read from the cache still answers; nothing is kept
                pass
        _LOADED[memo] = (path, text), compiled
        if not fresh:
            return compiled
        try:
            if getattr(compiled._executable._unloaded_executable, "host_callbacks", None):
                return compiled  # its callbacks are Python objects of this process
            serialized, in_tree, out_tree = serialize_executable.serialize(compiled)
            outputs = pickle.dumps(jax.tree.unflatten(out_tree, [0] * out_tree.num_leaves))
        except Exception:  # an executable that this backend or jax cannot serialize
            return compiled
        try:  # the arguments' tree, for a later run's load_ahead (a tree with static Python objects may not pickle)
            inputs = pickle.dumps(jax.tree.unflatten(in_tree, [0] * in_tree.num_leaves))
        except Exception:
            inputs = None
        _keep(path, {"text": text, "executable": serialized, "in_tree": inputs, "out_tree": outputs})
        return compiled

    def _compiled_afresh(self, args, as_nan):
        """The executable of ``args`` (arrays or ShapeDtypeStructs) compiled by XLA, JAX's
        persistent compilation cache bypassed, traced with failed checks as NaN where
        ``as_nan`` (the error mode the entry's text names). The body is jitted as a function
        of its own, so that neither its lowering nor its executable is one that JAX holds in
        memory (a ``Lowered`` and JAX's compilation memo answer with the executable read
        from the cache). The cache is turned off for the whole process meanwhile (JAX's
        switch is global, and JAX remembers its answer to "is the cache used" until
        ``reset_cache``), then turned back as it was, whatever fails on the way. One thread
        at a time turns it off (_AFRESH), so that two threads compiling afresh cannot leave
        it off; a program another thread compiles meanwhile only misses the cache."""
        body = self._body

        def afresh(*inner):
            return body(*inner)

        afresh.__name__ = afresh.__qualname__ = body.__name__  # the compiled program's name
        with _AFRESH:
            saved = jax.config.jax_enable_compilation_cache, _tracing._errors["as_nan"]
            try:
                jax.config.update("jax_enable_compilation_cache", False)
                compilation_cache.reset_cache()
                _tracing._errors["as_nan"] = as_nan
                return jax.jit(afresh, compiler_options=self._compiler_options).lower(*args).compile()
            finally:
                _tracing._errors["as_nan"] = saved[1]
                jax.config.update("jax_enable_compilation_cache", saved[0])
                compilation_cache.reset_cache()


# held while a program compiles with JAX's persistent cache turned off (_Program._compiled_afresh)
_AFRESH = threading.Lock()


def filter_jit(fn, name: str):
    """``equinox.filter_jit(fn)`` (array leaves of the arguments traced, every other leaf
    static), each structure of the arguments a :func:`jit` program keyed by the text of
    its tree structure and static leaves. PRNG keys travel as their key data."""
    plain = eqx.filter_jit(fn)
    programs = {}

    @functools.wraps(fn)
    def call(*args, **kwargs):
        leaves, treedef = jax.tree.flatten((args, kwargs))
        if directory() is None or any(isinstance(leaf, jax.core.Tracer) for leaf in leaves):
            return plain(*args, **kwargs)  # off, or inside another program's trace
        is_array = tuple(eqx.is_array(leaf) for leaf in leaves)
        keys = tuple(
            jax.random.key_impl(leaf) if array and jax.dtypes.issubdtype(leaf.dtype, jax.dtypes.prng_key) else None
            for array, leaf in zip(is_array, leaves)
        )
        static = tuple(None if array else leaf for array, leaf in zip(is_array, leaves))
        structure = (treedef, is_array, static, keys)
        if structure not in programs:

            def joined(*arrays):
                given = iter(arrays)
                leaves = [
                    (next(given) if impl is None else jax.random.wrap_key_data(next(given), impl=impl))
                    if array
                    else leaf
                    for array, leaf, impl in zip(is_array, static, keys)
                ]
                inner_args, inner_kwargs = jax.tree.unflatten(treedef, leaves)
                return fn(*inner_args, **inner_kwargs)

            programs[structure] = jit(joined, name, repr(structure))
        arrays = [
            leaf if impl is None else jax.random.key_data(leaf)
            for array, leaf, impl in zip(is_array, leaves, keys)
            if array
        ]
        return programs[structure](*arrays)

    return call


_REMEMBERED = {}  # (folder, name, structure) -> the answer


def remembered(name: str, structure: str, find):
    """``find()``, a fact about a program found from its trace (a small picklable value
    that depends on nothing but ``structure``, a text, and :func:`versions`), kept on disk
    beside the exported programs, so that a later process reads it instead of tracing
    again; found afresh where keeping is off or ``structure`` names an object's address
    (no stable text), and kept again where the entry is missing, damaged or for another
    text."""
    folder = directory()
    if folder is None or _ADDRESS.search(structure):
        return find()
    memo = (folder, name, structure)
    if memo not in _REMEMBERED:
        text = f"{name}\n{structure}\n{versions()}"
        path = folder / f"{name}-{hashlib.sha256(text.encode()).hexdigest()[:32]}.answer"
        try:
            entry = pickle.loads(path.read_bytes())
            found = entry["text"] == text
        except Exception:  # missing or damaged: found again
            found = False
        if found:
            _REMEMBERED[memo] = entry["answer"]
        else:
            _REMEMBERED[memo] = find()
            _keep(path, {"text": text, "answer": _REMEMBERED[memo]})
    return _REMEMBERED[memo]


def _aval(leaf, batch):
    """(shape, dtype name) of an argument leaf, the leading axis "batch" where it is one."""
    shape = tuple(np.shape(leaf))
    return (("batch", *shape[1:]) if batch and shape else shape), str(leaf.dtype)


_UNEXPORTABLE = (None, None)  # an entry that says export failed
_KEPT = {}  # (folder, name, structure, in_tree, avals) -> (Exported, out_tree) or None


def _kept(fn, name, structure, in_tree, avals):
    """(Exported, out_tree) of ``fn`` at ``avals``, read from disk or exported and kept;
    None when exporting is off, the structure has no stable text, or export fails."""
    folder = directory()
    if folder is None or _ADDRESS.search(structure) or _ADDRESS.search(str(in_tree)) or jax.device_count() > 1:
        return None  # off, no stable text, or devices that an entry for one device does not fit
    memo = (folder, name, structure, in_tree, avals)
    if memo not in _KEPT:
        text = f"{name}\n{structure}\n{in_tree}\n{avals}\n{versions()}"
        path = folder / f"{name}-{hashlib.sha256(text.encode()).hexdigest()[:32]}.jaxexport"
        _KEPT[memo] = _read(path, text) or _export(fn, in_tree, avals, path, text)
    return _KEPT[memo]


# Loading ahead (see load_ahead): {path: Future of (text, the loaded jax.stages.Compiled),
# or of None where it failed}; and the paths of the executables that the run since
# load_ahead read or kept, in order (None: no run).
_AHEAD = {}
_USED = None


def load_ahead(run: str) -> None:
    """Start loading the executables that the last run named ``run`` (a text naming the
    command, e.g. its arguments and folder) read or kept, in threads (as many as CPUs), so
    that a command's second run loads its programs side by side and while it reads its spec
    (XLA loads an executable without Python's lock: a quarter of a second of CPU apiece for
    the design solver's). :func:`_read_executable` takes an executable loaded ahead where
    its entry's text is the one asked for; what the run does not ask for is dropped at
    :func:`remember_run`. Nothing is loaded where keeping is off, on several devices,
    where no run of that name was remembered, or where this process holds it already; a
    failure here only leaves the run to load its executables itself."""
    global _USED
    folder = directory()
    _USED = []
    if folder is None:
        return
    try:
        names = pickle.loads(_run_path(folder, run).read_bytes())
    except Exception:  # no run of that name yet, or a damaged file: nothing ahead
        return
    if jax.device_count() > 1:  # asked only now: a run that loaded nothing leaves JAX's backend unstarted
        return
    _lapack_ready()
    backend = jax.devices()[0].client
    held = {place[0] for place, compiled in _LOADED.values() if compiled is not None}  # an earlier run here
    paths = [folder / str(name) for name in names]
    paths = [path for path in paths if path not in _AHEAD and path not in held]
    if not paths:
        return
    pool = ThreadPoolExecutor(min(len(paths), os.cpu_count() or 2), thread_name_prefix="magdesign load")
    try:
        for path in paths:
            _AHEAD[path] = pool.submit(_load, path, backend)
    except RuntimeError:  # no thread to be had: what was not submitted loads in the run
        pass
    finally:
        pool.shutdown(wait=False)


def remember_run(run: str, succeeded: bool = True) -> None:
    """Keep the names of the executables that this run (since :func:`load_ahead`) read or
    kept, for the next run named ``run``, where it ``succeeded`` (a failed or interrupted
    run's list may be cut short); drop the executables loaded ahead that it did not ask for."""
    global _USED
    folder, used, _USED = directory(), _USED, None
    _AHEAD.clear()
    if folder is None or not used or not succeeded:
        return
    names = [path.name for path in used if path.parent == folder]
    path = _run_path(folder, run)
    try:
        same = pickle.loads(path.read_bytes()) == names
    except Exception:  # not yet kept, or damaged: written
        same = False
    if not same:
        _keep(path, names)


def _run_path(folder, run):
    """The file of the executables' names of the run named ``run`` (see :func:`load_ahead`)."""
    text = f"{run}\n{versions()}"
    return folder / f"run-{hashlib.sha256(text.encode()).hexdigest()[:32]}.names"


def _load(path, backend):
    """(text, executable) of the entry kept at ``path``, loaded on ``backend`` for the
    arguments' tree that the entry keeps (a thread of :func:`load_ahead`), or None where
    it fails or the entry keeps no tree."""
    try:
        entry = pickle.loads(path.read_bytes())
        if entry.get("in_tree") is None:
            return None
        in_tree, out_tree = (jax.tree.structure(pickle.loads(entry[tree])) for tree in ("in_tree", "out_tree"))
        return entry["text"], serialize_executable.deserialize_and_load(entry["executable"], in_tree, out_tree, backend)
    except Exception:  # any failure: the run reads the entry itself
        return None


def _loaded_ahead(path, text):
    """The executable :func:`load_ahead` loaded from ``path`` for ``text`` (waiting for its
    thread), or None where none was or it is for another text. The text names the
    arguments' tree, so an executable for the text takes the caller's arguments."""
    ahead = _AHEAD.pop(path, None)
    loaded = None if ahead is None else ahead.result()
    return loaded[1] if loaded is not None and loaded[0] == text else None


def _read_executable(path, text, in_tree):
    """The executable kept at ``path`` for ``text``, loaded for arguments of ``in_tree``
    (by :func:`load_ahead` where it was), or None where it is missing, unreadable, for
    another text or fails to load."""
    ahead = _loaded_ahead(path, text)
    if ahead is not None:
        return ahead
    try:
        entry = pickle.loads(path.read_bytes())
        if entry["text"] != text:
            return None
        _lapack_ready()
        out_tree = jax.tree.structure(pickle.loads(entry["out_tree"]))
        return serialize_executable.deserialize_and_load(entry["executable"], in_tree, out_tree)
    except Exception:  # any damage to the file is a miss: the executable is compiled again
        return None


def _read(path, text):
    """The entry at ``path`` for ``text``, or None where it is missing, unreadable or for
    another text (other versions, another structure)."""
    try:
        entry = pickle.loads(path.read_bytes())
        if entry["text"] != text:
            return None
        if entry["exported"] is None:
            return _UNEXPORTABLE
        _lapack_ready()
        return jax.export.deserialize(bytearray(entry["exported"])), jax.tree.structure(pickle.loads(entry["out_tree"]))
    except Exception:  # any damage to the file is a miss: the entry is made again
        return None


# The two extension modules whose function pointers are jaxlib's LAPACK kernels on CPU.
_LAPACK_MODULES = ("scipy.linalg.cython_blas", "scipy.linalg.cython_lapack")


@functools.cache
def _lapack_ready():
    """Set up jaxlib's LAPACK kernels, as lowering a LAPACK call does: a program read back
    from disk is never lowered, and its LAPACK calls would run unset kernels (a crash).

    jaxlib takes the kernels from scipy's two modules of LAPACK and BLAS pointers
    (_LAPACK_MODULES). Imported by name they run the whole of ``scipy.linalg`` first (a
    quarter of a second, more than loading a kept program); here they are loaded alone for
    the set-up and then dropped from ``sys.modules``, so that a later ``import
    scipy.linalg`` loads its package whole as usual. Where that fails (another jaxlib),
    the kernels are set up as jax does, by lowering a LAPACK call."""
    added = []
    try:
        from jaxlib.cpu import _lapack

        for name in _LAPACK_MODULES:
            if name not in sys.modules:
                parent = importlib.util.find_spec(name.rpartition(".")[0])
                spec = importlib.machinery.PathFinder.find_spec(name, parent.submodule_search_locations)
                sys.modules[name] = importlib.util.module_from_spec(spec)
                added.append(name)
                spec.loader.exec_module(sys.modules[name])
        _lapack.initialize()
        return
    except Exception:  # not this jaxlib's or scipy's layout
        pass
    finally:
        for name in added:
            del sys.modules[name]
    jax.jit(jnp.linalg.eigh).lower(np.eye(2))


def _export(fn, in_tree, avals, path, text):
    """Export ``fn`` at ``avals`` (a batch axis symbolic), write the entry to ``path`` and
    return it read back (the program that later processes read, so that they find the same
    compiled program in the compilation cache); _UNEXPORTABLE, also written, where export
    fails."""
    out_trees = []

    def flat(*leaves):
        out = fn(*jax.tree.unflatten(in_tree, leaves))
        out_leaves, out_tree = jax.tree.flatten(out)
        out_trees.append(out_tree)
        return out_leaves

    (size,) = jax.export.symbolic_shape("batch") if any("batch" in shape for shape, _ in avals) else (None,)
    shapes = [
        jax.ShapeDtypeStruct(tuple(size if axis == "batch" else axis for axis in shape), dtype)
        for shape, dtype in avals
    ]
    try:
        serialized = jax.export.export(jax.jit(flat))(*shapes).serialize()
    except Exception:  # not exportable (a host callback, a batch that export cannot keep symbolic)
        _keep(path, {"text": text, "exported": None})  # later processes trace it without trying
        return _UNEXPORTABLE
    # the output's tree as an instance with 0 for each leaf: a pickled tree structure of
    # equinox modules does not unflatten in another process
    out_tree = pickle.dumps(jax.tree.unflatten(out_trees[-1], [0] * out_trees[-1].num_leaves))
    _keep(path, {"text": text, "exported": bytes(serialized), "out_tree": out_tree})
    return jax.export.deserialize(serialized), jax.tree.structure(pickle.loads(out_tree))


def _keep(path, entry):
    """Write ``entry`` to ``path`` whole or not at all (another process may read it); a
    folder that cannot be written keeps nothing."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".part")
        try:
            with os.fdopen(handle, "wb") as file:
                file.write(pickle.dumps(entry))
            os.replace(temporary, path)
        finally:
            Path(temporary).unlink(missing_ok=True)
    except OSError:
        pass
