"""Soft-magnetic bodies by the method of moments.

A soft body (its own frame: centre at the origin) is split into N equal cuboid cells on
a regular grid, each of uniform magnetisation M_i (A/m). The field of a cell is exact
(:func:`magdesign.fields.cuboid_tensor`: B = T J, J = mu0 M); requiring M = chi H at the
cells' centres c_i (collocation) gives 3N linear equations

    M_i = chi (H_ext(c_i) + sum_j (T(c_i - c_j) - delta_ij 1) M_j)
    (1 - chi (T - 1)) M = chi H_ext,          chi = mu_r - 1,

solved by LU (``jax.scipy.linalg.solve``). T depends on the cells' index differences only, so it is
evaluated once per difference on the grid, (2 n_x - 1)(2 n_y - 1)(2 n_z - 1) tensors,
not N^2. Equal cells make one body's system symmetric, which is what makes the co-energy's
gradient the force (below); the blocks between bodies of unequal or turned cells are not
each other's transposes, so no co-energy (and no force) is offered for coupled bodies.

Shapes: a cuboid is filled exactly; a sphere or cylinder (axis along z) keeps the cells
whose centres lie inside and stretches the grid so that the cells' total volume is the
body's (a cylinder keeps its length and its cross-section's area); the staircase's shape
error remains. The error of the collocation and of the staircase falls like the cell size
at high permeability (slower than that for a staircase sphere); tests/fields/test_soft.py and ``magdesign
accuracy`` show how fast against exact answers.

Force and torque. For a linear body in the field of fixed sources the magnetic
co-energy is W' = (mu0 / 2) int M . H_ext dV = (1/2) sum_i V M_i . B_ext(c_i); the force
along any pose coordinate q is dW'/dq at fixed sources (``jax.grad`` of
:func:`coenergy` through the solve: no hand-derived force formula).

Saturation (optional, ``saturation`` = J_s = mu0 M_s in T, e.g. 2.2 T for Fe, ~0.8 T for
Ni-Fe): each cell follows the isotropic, anhysteretic law

    J = chi h / sqrt(1 + (chi |h| / J_s)^2),          J = mu0 M, h = mu0 H (T),

of initial slope chi and limit J_s (linear as J_s -> inf). The equations above then are
nonlinear; they are solved by Newton's method with a backtracking line search
(:mod:`magdesign._newton`, the loop of the dome's equilibrium too) from the linear answer
pulled onto the law, judged on their residual (a solve that does not converge raises an
error naming it), with derivatives by the implicit function theorem. Newton's step solves
with the law's Jacobian written out (a 3 x 3 block per cell), not one built from 3N
forward passes; a plain Newton step, without the line search, overshoots where the law's
slope falls from chi to ~0. The co-energy keeps its meaning: W' = sum_i V (J_i . B_ext,i
+ (1/2) J_i . ((T - 1) J)_i - w(J_i)) / mu0 with the law's energy density
w(J) = (J_s^2 / chi) (1 - sqrt(1 - |J|^2 / J_s^2)) (w'(J) = h), which equals
(1/2) sum_i V M_i . B_ext,i for a linear body and is stationary in J at the solution, so its
pose derivative is again the force.

Several bodies (:func:`coupled_magnetization`) magnetise one another: one system holds all
their cells, the blocks between two bodies evaluated pair by pair in the bodies' own frames.

Not modelled: hysteresis and remanence of the soft parts; the cells' own shape inside
curved bodies (staircase). A linear body's mean magnetisation to ~0.1 %, with an error
estimate, comes from the surface formulation of :mod:`magdesign.fields.soft_surface`.
"""

import warnings
from typing import Literal

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.scipy as jsp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from magdesign import _newton
from magdesign._numerics import float_array
from magdesign._tracing import checked
from magdesign._validation import check_last_axis, check_positive, check_scalar
from magdesign.fields.cells import cells_field, kernel_batches
from magdesign.fields.cuboid import cuboid_tensor
from magdesign.units import MU0

# Saturating soft bodies: Newton's method on the cells' polarisation J (T)
# with a backtracking line search, stopped when the residual's largest entry is below
# SATURATION_RESIDUAL (T). Its rounding is about chi eps |J| (chi up to ~1e4, |J| up to
# ~2 T: ~4e-12 T). A step is halved until |r|^2 falls by SATURATION_ARMIJO times the
# step's fraction (Armijo's sufficient decrease), at most
# magdesign._newton.HALVINGS times.
SATURATION_RESIDUAL = 1e-9
SATURATION_MAX_STEPS = 100
SATURATION_ARMIJO = 1e-4


# The shapes and how many lengths (m) a spec's size holds (cuboid: full sides x, y, z;
# cylinder: diameter, length; sphere: diameter).
SIZE_LENGTHS = {"cuboid": 3, "cylinder": 2, "sphere": 1}
# The keywords that size each shape in the Python API, as the field functions do: round
# bodies by radius (and height along the axis), blocks by their full sides.
SIZE_KEYWORDS = {"cuboid": ("dimension",), "cylinder": ("radius", "height"), "sphere": ("radius",)}
# The most cells a body may have: its dense system is (3N)^2 float64 (N = 6000: 2.6 GB).
MAX_CELLS = 6000


class SoftBody(eqx.Module):
    """A soft-magnetic body (linear, or saturating) as equal cuboid cells on a regular grid,
    in its own frame (centre at the origin).

    Fields:
        cell: the cells' side lengths (m), shape (3,).
        permeability: relative permeability mu_r (> 0; chi = mu_r - 1).
        grid: (static) cells along x, y, z of the grid that holds the body.
        index: (static) the grid indices of the body's cells, N rows of (i, j, k).
        saturation: saturation polarisation J_s = mu0 M_s (T, > 0), or None: linear.
    """

    cell: Float[Array, "3"]
    permeability: Float[Array, ""]
    grid: tuple[int, int, int] = eqx.field(static=True)
    index: tuple[tuple[int, int, int], ...] = eqx.field(static=True)
    saturation: Float[Array, ""] | None = None

    @property
    def centres(self) -> Float[Array, "n 3"]:
        """The cells' centres (m), shape (N, 3), body frame."""
        offset = (np.asarray(self.index) - (np.asarray(self.grid) - 1) / 2.0).astype(float)
        return jnp.asarray(offset) * self.cell

    @property
    def cell_volume(self) -> Float[Array, ""]:
        return jnp.prod(self.cell)

    @property
    def volume(self) -> Float[Array, ""]:
        return len(self.index) * self.cell_volume


def size_keywords(shape: str, size: Float[ArrayLike, "..."]) -> dict:
    """The keywords of :func:`soft_body` for a spec's ``size`` of a ``shape`` (SIZE_LENGTHS:
    a cuboid's full sides, a cylinder's diameter and length, a sphere's diameter; m)."""
    if shape not in SIZE_LENGTHS:
        raise ValueError(f"shape must be one of {tuple(SIZE_LENGTHS)}, got {shape!r}")
    size = float_array(size).reshape(-1)
    if size.shape != (SIZE_LENGTHS[shape],):
        raise ValueError(f"size of a {shape} must hold {SIZE_LENGTHS[shape]} length(s) (m), got shape {size.shape}")
    if shape == "cuboid":
        return {"dimension": size}
    return {"radius": 0.5 * size[0], "height": size[1]} if shape == "cylinder" else {"radius": 0.5 * size[0]}


def soft_body(
    shape: Literal["cuboid", "cylinder", "sphere"],
    size: Float[ArrayLike, "..."] | None = None,
    *,
    cells: int | tuple[int, int, int],
    permeability: float | Float[ArrayLike, ""],
    saturation: float | Float[ArrayLike, ""] | None = None,
    radius: Float[ArrayLike, ""] | None = None,
    height: Float[ArrayLike, ""] | None = None,
    dimension: Float[ArrayLike, "3"] | None = None,
) -> SoftBody:
    """A soft body split into cells, in its own frame (centre at the origin).

    Args:
        shape: "cuboid" (``dimension=``: full sides x, y, z), "cylinder" (``radius=``,
            ``height=``; axis along z) or "sphere" (``radius=``), as the field functions
            size their bodies (docs/models.md, "Conventions").
        radius, height, dimension: the sizes (m), each > 0, the ones ``shape`` takes. May
            be traced (the cells scale with them).
        size: deprecated (it warns): the sizes as a spec writes them, a cuboid's full
            sides, a cylinder's diameter and length, a sphere's diameter (m); see
            :func:`size_keywords`.
        cells: cells along the body's longest side (the others in proportion, at least
            one), or (n_x, n_y, n_z) explicitly.
        permeability: relative permeability mu_r (> 0).
        saturation: saturation polarisation J_s = mu0 M_s (T, > 0; e.g. 2.2 T for Fe),
            or None (default) for a linear body.

    Returns:
        The :class:`SoftBody`. Its number of cells is ``len(body.index)``.
    """
    if shape not in SIZE_LENGTHS:
        raise ValueError(f"shape must be one of {tuple(SIZE_LENGTHS)}, got {shape!r}")
    if size is not None:
        wanted = " and ".join(f"{name}=" for name in SIZE_KEYWORDS[shape])
        warnings.warn(
            f"soft_body(shape, size) is deprecated (size holds diameters); give a {shape} its {wanted} "
            f"(soft.size_keywords(shape, size) converts)",
            DeprecationWarning,
            stacklevel=2,
        )
        if radius is not None or height is not None or dimension is not None:
            raise TypeError("soft_body(): give size or radius= / height= / dimension=, not both")
        radius, height, dimension = (size_keywords(shape, size).get(n) for n in ("radius", "height", "dimension"))
    sides = _sides(shape, radius=radius, height=height, dimension=dimension)
    check_positive(permeability=permeability)
    if saturation is not None:
        check_positive(saturation=saturation, unit="T")
        check_positive(**{"permeability - 1 (a saturating body needs mu_r > 1)": jnp.asarray(permeability) - 1.0})
        saturation = jnp.asarray(saturation, dtype=sides.dtype)
    grid = _grid(sides, cells)
    indices = np.indices(grid).reshape(3, -1).T
    centre = (indices - (np.asarray(grid) - 1) / 2.0) / np.asarray(grid)  # in body sides
    radius2 = centre[:, 0] ** 2 + centre[:, 1] ** 2
    inside = {
        "cuboid": np.ones(len(centre), bool),
        "cylinder": radius2 < 0.25,
        "sphere": radius2 + centre[:, 2] ** 2 < 0.25,
    }[shape]
    if not inside.any():
        raise ValueError(f"cells: {cells!r} puts no cell centre inside the {shape}; ask for more cells")
    if inside.sum() > MAX_CELLS:
        raise ValueError(
            f"cells: {cells!r} gives {inside.sum()} cells, more than the {MAX_CELLS} a dense solve holds; ask for fewer"
        )
    index = tuple(tuple(int(i) for i in row) for row in indices[inside])
    cell = sides / jnp.asarray(grid, dtype=sides.dtype)
    # curved bodies: the kept cells' volume made the body's (a cylinder keeps its length)
    if shape == "cylinder":
        filled = inside.sum() / grid[2]  # cells in one cross-section
        cell = cell.at[:2].multiply(np.sqrt(np.pi / 4 * grid[0] * grid[1] / filled))
    elif shape == "sphere":
        cell = cell * (np.pi / 6 * np.prod(grid) / inside.sum()) ** (1.0 / 3.0)
    return SoftBody(
        cell=cell,
        permeability=jnp.asarray(permeability, dtype=cell.dtype),
        grid=grid,
        index=index,
        saturation=saturation,
    )


def _sides(shape, **sizes):
    """The full sides (3,) (m) of the box that holds a ``shape`` of the given sizes (the
    keywords of SIZE_KEYWORDS[shape], each checked)."""
    wanted = SIZE_KEYWORDS[shape]
    given = [name for name, value in sizes.items() if value is not None]
    if sorted(given) != sorted(wanted):
        names = " and ".join(f"{name}=" for name in wanted)
        raise ValueError(f"a {shape} takes {names} (m), got {', '.join(f'{n}=' for n in given) or 'none'}")
    if shape == "cuboid":
        check_last_axis("dimension", sizes["dimension"], 3)
        sides = float_array(sizes["dimension"])
        if sides.shape != (3,):
            raise ValueError(f"dimension must have shape (3,), got shape {sides.shape}")
        check_positive(dimension=sides, unit="m")
        return sides
    check_scalar("one body per call", **{name: sizes[name] for name in wanted})
    check_positive(unit="m", **{name: sizes[name] for name in wanted})
    diameter = 2.0 * float_array(sizes["radius"])
    length = float_array(sizes["height"]) if shape == "cylinder" else diameter
    return jnp.stack([diameter, diameter, length.astype(diameter.dtype)])


def _grid(sides, cells):
    if isinstance(cells, (tuple, list)):
        grid = tuple(int(n) for n in cells)
        if len(grid) != 3 or min(grid) < 1:
            raise ValueError(f"cells must be a positive integer or three of them, got {cells!r}")
        return grid
    if int(cells) < 1:
        raise ValueError(f"cells must be a positive integer or three of them, got {cells!r}")
    try:
        ratio = np.asarray(sides) / np.max(np.asarray(sides))
    except Exception:  # traced sizes: the grid needs concrete proportions
        raise ValueError("cells: with a traced size give the grid as (n_x, n_y, n_z)") from None
    return tuple(max(1, int(round(int(cells) * r))) for r in ratio)


def _differences(body):
    """Index differences c_i - c_j, shifted to be >= 0 (N, N, 3), and the grid of all
    differences (2 g - 1 per axis)."""
    index = np.asarray(body.index)
    span = 2 * np.asarray(body.grid) - 1
    difference = index[:, None, :] - index[None, :, :] + (np.asarray(body.grid) - 1)
    return np.ravel_multi_index(difference.reshape(-1, 3).T, span).reshape(len(index), len(index)), span


def _table(body):
    """T for every index difference on the grid (prod(2 g - 1), 3, 3), and for each pair
    of cells the row of its difference (N, N)."""
    flat, span = _differences(body)
    steps = jnp.asarray(np.indices(span).reshape(3, -1).T - (np.asarray(body.grid) - 1), dtype=body.cell.dtype)
    table = kernel_batches(lambda step: cuboid_tensor(step * body.cell, dimension=body.cell), steps, 1)
    return table, flat


def interaction(body: SoftBody) -> Float[Array, "n3 n3"]:
    """The block matrix of T(c_i - c_j) (dimensionless), shape (3N, 3N): B at c_i from
    cell j is its 3x3 block times J_j (T). Symmetric."""
    table, flat = _table(body)
    n = len(body.index)
    return table[flat].transpose(0, 2, 1, 3).reshape(3 * n, 3 * n)


def magnetization(body: SoftBody, external: Float[ArrayLike, "n 3"]) -> Float[Array, "n 3"]:
    """The cells' self-consistent magnetisation M (A/m), shape (N, 3).

    Args:
        body: the :class:`SoftBody`.
        external: the flux density of every other source at the cells' centres
            (``body.centres``), B_ext = mu0 H_ext (T), shape (N, 3), body frame.

    Raises:
        ValueError: ``external`` is not of shape (N, 3).
        RuntimeError: a saturating body's solve does not converge; the message names the
            saturation solve. Raised at run time, also under jit (equinox's
            ``EquinoxRuntimeError``, or jax's ``JaxRuntimeError`` from a compiled function).
    """
    external = _external_of(body, external)
    return _solve(interaction(body), [body], external) / MU0


def coupled_magnetization(
    bodies: list[SoftBody],
    centres: list[Float[ArrayLike, "3"]],
    matrices: list[Float[ArrayLike, "3 3"]],
    externals: list[Float[ArrayLike, "n 3"]],
) -> list[Float[Array, "n 3"]]:
    """The magnetisation M (A/m) of several soft bodies that magnetise one another, each
    (N_b, 3) in its own frame.

    Args:
        bodies: the :class:`SoftBody` s.
        centres: each body's centre (3,) (m, scene frame).
        matrices: each body's rotation (3, 3): v_body = matrix v_scene.
        externals: the flux density of the other sources (not these bodies) at each body's
            cell centres (T), (N_b, 3), in that body's frame.

    Raises:
        ValueError: an entry of ``externals`` is not of its body's shape (N_b, 3).
        RuntimeError: a saturating body's solve does not converge, as in :func:`magnetization`.
    """
    externals = [_external_of(body, external) for body, external in zip(bodies, externals)]
    centres = [float_array(centre) for centre in centres]
    matrices = [float_array(matrix) for matrix in matrices]
    rows = [
        jnp.concatenate(
            [
                interaction(a) if i == k else _cross_interaction(a, centres[i], matrices[i], b, centres[k], matrices[k])
                for k, b in enumerate(bodies)
            ],
            axis=1,
        )
        for i, a in enumerate(bodies)
    ]
    polarization = _solve(jnp.concatenate(rows, axis=0), bodies, jnp.concatenate(externals))
    ends = np.cumsum([len(body.index) for body in bodies])[:-1]
    return [part / MU0 for part in jnp.split(polarization, ends)]


def _external_of(body, external):
    external = float_array(external)
    n = len(body.index)
    if external.shape != (n, 3):
        raise ValueError(
            f"external must hold the field at the body's {n} cell centres, shape ({n}, 3); got {external.shape}"
        )
    return external


def _cross_interaction(a, centre_a, matrix_a, b, centre_b, matrix_b):
    """The (3 N_a, 3 N_b) block taking b's cells' polarisation (T, b's frame) to the flux
    density at a's cell centres (T, a's frame)."""
    points = centre_a + a.centres @ matrix_a  # a's centres, scene frame
    local = (points - centre_b) @ matrix_b.T  # in b's frame
    steps = (local[:, None, :] - b.centres[None, :, :]).reshape(-1, 3)
    tensors = kernel_batches(lambda step: cuboid_tensor(step, dimension=b.cell), steps, 1)
    tensors = tensors.reshape(len(a.index), len(b.index), 3, 3)
    turned = jnp.einsum("kl,ijlm->ikjm", matrix_a @ matrix_b.T, tensors)
    return turned.reshape(3 * len(a.index), 3 * len(b.index))


def _per_cell(bodies):
    """Per cell: chi (N, 1) and J_s (N, 1) (T; inf for a linear body)."""
    chi = jnp.concatenate([jnp.full((len(b.index), 1), b.permeability - 1.0) for b in bodies])
    limit = jnp.concatenate(
        [jnp.full((len(b.index), 1), jnp.inf if b.saturation is None else b.saturation) for b in bodies]
    )
    return chi, limit


def law(h: Float[ArrayLike, "... 3"], chi, saturation) -> Float[Array, "... 3"]:
    """The saturation law J(h) = chi h / sqrt(1 + (chi |h| / J_s)^2) (T), h = mu0 H (T,
    (..., 3)); ``saturation`` J_s (T; inf: linear), ``chi`` = mu_r - 1, both broadcast
    against h's leading axes."""
    h = jnp.asarray(h)
    return chi * h / jnp.sqrt(1.0 + jnp.sum((chi * h / saturation) ** 2, axis=-1, keepdims=True))


def _solve(matrix, bodies, external):
    """The cells' polarisation J = mu0 M (T), (N, 3), for the interaction ``matrix``
    (3N, 3N) of ``bodies`` and the external flux density (N, 3) (T)."""
    n = external.shape[0]
    chi, limit = _per_cell(bodies)
    rows = jnp.repeat(chi[:, 0], 3)
    system = jnp.eye(3 * n) - rows[:, None] * (matrix - jnp.eye(3 * n))
    linear = jsp.linalg.solve(system, rows * external.reshape(-1)).reshape(n, 3)
    if all(body.saturation is None for body in bodies):
        return linear
    # the start: the linear answer pulled onto the law (|J| < J_s)
    start = law(linear, 1.0, limit)
    polarization, failed = _saturated(matrix, external, chi, limit, start)
    return checked(
        polarization,
        failed,
        f"soft-magnetic saturation: the solve of the cells' magnetisation did not converge in {SATURATION_MAX_STEPS} "
        f"steps (its residual stayed above {SATURATION_RESIDUAL:g} T; check the saturation and the field's size)",
    )


def _demagnetising(matrix, polarization):
    """(T - 1) J: mu0 H of the cells' own polarisation J (N, 3) (T) at their centres."""
    return (matrix @ polarization.reshape(-1)).reshape(polarization.shape) - polarization


def _residual(polarization, matrix, external, chi, limit):
    """J - law(h(J)), h = B_ext + (T - 1) J at the cells (N, 3) (T)."""
    return polarization - law(external + _demagnetising(matrix, polarization), chi, limit)


def _residual_jacobian(polarization, matrix, external, chi, limit):
    """d residual / d J (3N, 3N): 1 - law'(h) (T - 1), law' a 3 x 3 block per cell."""
    n = external.shape[0]
    h = external + _demagnetising(matrix, polarization)
    slope = jax.vmap(jax.jacfwd(law))(h, chi, limit)  # (N, 3, 3)
    coupled = jnp.einsum("nij,njm->nim", slope, (matrix - jnp.eye(3 * n)).reshape(n, 3, 3 * n))
    return jnp.eye(3 * n) - coupled.reshape(3 * n, 3 * n)


@jax.custom_jvp
def _saturated(matrix, external, chi, limit, start):
    """(J (N, 3) (T), failed): Newton's method from ``start`` with a backtracking (Armijo)
    line search on |residual|^2 (plain Newton overshoots where the law's slope falls from
    chi to ~0), stopped when the largest residual is below SATURATION_RESIDUAL (T);
    derivatives by the implicit function theorem (the rule below), exact to any order."""
    args = (matrix, external, chi, limit)

    def measure(polarization):
        residual = _residual(polarization, *args)
        return residual, jnp.sum(residual**2)

    def linearise(polarization, measured, gave_up, steps):
        residual, _ = measured
        done = ~((jnp.max(jnp.abs(residual)) > SATURATION_RESIDUAL) & (steps < SATURATION_MAX_STEPS))
        return done, residual, steps + jnp.where(done, 0, 1)

    def direction(polarization, residual, steps):
        jacobian = _residual_jacobian(polarization, *args)

        def too_long(fraction, trial, base):  # Armijo's test on |residual|^2
            return trial[1] > (1.0 - SATURATION_ARMIJO * fraction) * base[1]

        return -jnp.linalg.solve(jacobian, residual.reshape(-1)).reshape(residual.shape), too_long, steps

    polarization, (residual, _), _, _ = _newton.newton(linearise, direction, measure, start, measure(start), 0)
    return polarization, ~(jnp.max(jnp.abs(residual)) <= SATURATION_RESIDUAL)


@_saturated.defjvp
def _saturated_jvp(primals, tangents):
    polarization, failed = _saturated(*primals)
    matrix, external, chi, limit, _ = primals
    _, moved = jax.jvp(lambda *args: _residual(polarization, *args), primals[:4], tangents[:4])
    jacobian = _residual_jacobian(polarization, matrix, external, chi, limit)
    change = -jnp.linalg.solve(jacobian, moved.reshape(-1)).reshape(polarization.shape)
    return (polarization, failed), (change, np.zeros((), dtype=jax.dtypes.float0))


def field(
    body: SoftBody, magnetization: Float[ArrayLike, "n 3"], points: Float[ArrayLike, "... 3"]
) -> Float[Array, "... 3"]:
    """The body's own flux density B (T) at ``points`` (m, body frame, shape (..., 3)),
    given its cells' magnetisation (A/m, (N, 3)). Inside a cell B = mu0 (H + M)."""
    return cells_field(points, centres=body.centres, dimension=body.cell, polarization=MU0 * float_array(magnetization))


def coenergy(body: SoftBody, external: Float[ArrayLike, "n 3"]) -> Float[Array, ""]:
    """The magnetic co-energy W' (J) of the body in the field of fixed sources, M solved
    self-consistently; ``external`` as in :func:`magnetization`. Linear body:
    (1/2) sum_i V M_i . B_ext(c_i); saturating body: the module docstring's form. Its
    derivative with respect to any pose coordinate of the body (at fixed sources) is the
    generalised force along it (N, or N m for an angle)."""
    external = _external_of(body, external)
    matrix = interaction(body)
    polarization = _solve(matrix, [body], external)
    if body.saturation is None:
        return 0.5 * body.cell_volume * jnp.sum(polarization * external) / MU0
    chi, limit = body.permeability - 1.0, body.saturation
    # < 1 on the law; clipped where the solve's tolerance lets |J| reach J_s (chi |h| / J_s ~ 1e4)
    fraction = jnp.minimum(jnp.sum(polarization**2, axis=-1) / limit**2, 1.0)
    density = (limit**2 / chi) * fraction / (1.0 + jnp.sqrt(1.0 - fraction))  # w(J), no cancellation
    own = _demagnetising(matrix, polarization)
    total = jnp.sum(polarization * external) + 0.5 * jnp.sum(polarization * own) - jnp.sum(density)
    return body.cell_volume * total / MU0


def demagnetizing_tensor(body: SoftBody) -> Float[Array, "3 3"]:
    """The body's magnetometric demagnetising tensor as the cells see it: -(the mean over
    the cells of H at their centres) / M for a uniform M (dimensionless, trace ~1). It
    tends to the exact magnetometric factors as the cells shrink."""
    table, flat = _table(body)
    counts = np.bincount(flat.reshape(-1), minlength=table.shape[0])
    n = len(body.index)
    return jnp.eye(3) - jnp.einsum("d,dij->ij", jnp.asarray(counts, dtype=table.dtype), table) / n
