"""A zoo of constrained problems with published optima, as magdesign design problems.

Problems of the Hock-Schittkowski collection (W. Hock, K. Schittkowski, "Test Examples for
Nonlinear Programming Codes", Lecture Notes in Economics and Mathematical Systems 187,
Springer 1981), numbered as there, each with its published start and optimum (or, where
the comment beside a problem says so, a refined one). The model
returns the objective "f", the inequality constraints "g1", ... (each g >= 0 in the book,
given here as a Limit with lower 0) and the equalities "h1", ... (Target 0, scale 1).
magdesign variables need finite bounds: where the book has none, a box far from the
optimum is added ("box"), which leaves the problem's solution unchanged.

A problem whose published start lies outside a bound is started on that bound. Left out:
hs002, hs016 and hs020, where from the published start (moved onto its bound) the solver
ends, "successful", at another local minimum of the book's problem (a vertex of a bound and a
limit, checked by hand); hs013, whose optimum is no KKT point; and hs049, whose minimum is
flat to sixth order: the solver ends "successful" with f = 5e-24, but x only within 3e-6 of
x*. hs046 and hs047 (degenerate minima on curved equalities) are in: the solver's
radius, nonmonotone merit and bent steps finish them within the default 100 model
evaluations (89 and 72; before those, hs046 took 322 and hs047 was unfinished at 2000).
"""

import math
from dataclasses import dataclass, field

import jax.numpy as jnp
import numpy as np
from jax.scipy.special import ndtr

from magdesign.design import Limit, Objective, Problem, Target, Variable


@dataclass(frozen=True)
class Published:
    """A published problem: objective f(x), g(x) >= 0, h(x) == 0 on a list x."""

    name: str
    f: object
    bounds: list  # [(lower, upper)] per variable
    start: list
    optimum: list
    value: float
    g: list = field(default_factory=list)
    h: list = field(default_factory=list)

    def problem(self) -> Problem:
        names = [f"x{i + 1}" for i in range(len(self.bounds))]

        def model(v):
            x = [v[name] for name in names]
            outputs = {"f": self.f(x)}
            outputs.update({f"g{i + 1}": g(x) for i, g in enumerate(self.g)})
            outputs.update({f"h{i + 1}": h(x) for i, h in enumerate(self.h)})
            return outputs

        variables = [
            Variable(name, lo, hi, start=float(np.clip(x0, lo, hi)))
            for name, (lo, hi), x0 in zip(names, self.bounds, self.start)
        ]
        return Problem(
            model,
            variables,
            targets=[Target(f"h{i + 1}", 0.0, scale=1.0) for i in range(len(self.h))],
            limits=[Limit(f"g{i + 1}", lower=0.0, scale=1.0) for i in range(len(self.g))],
            objective=Objective("f", sense="min"),
        )


def rosenbrock(x):
    return 100.0 * (x[1] - x[0] ** 2) ** 2 + (1.0 - x[0]) ** 2


BOX = 100.0
SQRT2, SQRT3, SQRT7 = math.sqrt(2.0), math.sqrt(3.0), math.sqrt(7.0)
# hs011's optimum lies on x2 = x1^2, where 2 x1^3 + x1 - 5 = 0 (Cardano's root; the book
# gives 1.23467971, 1.52443370).
HS011_X1 = math.cbrt(1.25 + math.sqrt(25.0 / 16.0 + 1.0 / 216.0)) + math.cbrt(
    1.25 - math.sqrt(25.0 / 16.0 + 1.0 / 216.0)
)

# hs019's optimum is where its two circles meet: subtracting their equations gives
# x1 = 14.095 (the book's value, exactly), and the lower root of the first then x2
# (the book gives 0.84296079).
HS019_X2 = 5.0 - math.sqrt(100.0 - 9.095**2)

# hs057's data (the book's a_i and b_i, i = 1..44)
HS057_A = np.array(
    [8] * 2
    + [10] * 4
    + [12] * 4
    + [14] * 3
    + [16] * 3
    + [18] * 2
    + [20] * 3
    + [22] * 3
    + [24] * 3
    + [26] * 3
    + [28] * 2
    + [30] * 3
    + [32] * 2
    + [34]
    + [36] * 2
    + [38] * 2
    + [40]
    + [42],
    dtype=float,
)
HS057_B = np.array(
    [
        0.49,
        0.49,
        0.48,
        0.47,
        0.48,
        0.47,
        0.46,
        0.46,
        0.45,
        0.43,
        0.45,
        0.43,
        0.43,
        0.44,
        0.43,
        0.43,
        0.46,
        0.45,
        0.42,
        0.42,
        0.43,
        0.41,
        0.41,
        0.40,
        0.42,
        0.40,
        0.40,
        0.41,
        0.40,
        0.41,
        0.41,
        0.40,
        0.40,
        0.40,
        0.38,
        0.41,
        0.40,
        0.40,
        0.41,
        0.38,
        0.40,
        0.40,
        0.39,
        0.39,
    ]
)


def hs095_family(name, b):
    """hs095 to hs098: a linear objective on a box, under four bilinear limits c_i(x) >= b_i
    that differ only in b. Each optimum holds one limit with every variable but one on a
    bound, so that variable solves that limit's (linear) equation: x6 = b1 / 1495.5 in
    hs095 and hs096; x1 from c1 = b1 with x5, x6 on their upper bounds in hs097 and hs098
    (the book gives 0.00332331 and 0.2685649)."""
    c = [
        lambda x: (
            17.1 * x[0]
            + 38.2 * x[1]
            + 204.2 * x[2]
            + 212.3 * x[3]
            + 623.4 * x[4]
            + 1495.5 * x[5]
            - 169.0 * x[0] * x[2]
            - 3580.0 * x[2] * x[4]
            - 3810.0 * x[3] * x[4]
            - 18500.0 * x[3] * x[5]
            - 24300.0 * x[4] * x[5]
        ),
        lambda x: (
            17.9 * x[0]
            + 36.8 * x[1]
            + 113.9 * x[2]
            + 169.7 * x[3]
            + 337.8 * x[4]
            + 1385.2 * x[5]
            - 139.0 * x[0] * x[2]
            - 2450.0 * x[3] * x[4]
            - 16600.0 * x[3] * x[5]
            - 17200.0 * x[4] * x[5]
        ),
        lambda x: -273.0 * x[1] - 70.0 * x[3] - 819.0 * x[4] + 26000.0 * x[3] * x[4],
        lambda x: 159.9 * x[0] - 311.0 * x[1] + 587.0 * x[3] + 391.0 * x[4] + 2198.0 * x[5] - 14000.0 * x[0] * x[5],
    ]
    upper = [0.31, 0.046, 0.068, 0.042, 0.028, 0.0134]
    if b[0] < 10.0:  # hs095, hs096 (b1 = 4.97; hs097, hs098: 32.97)
        optimum = [0.0] * 5 + [b[0] / 1495.5]
    else:  # hs097, hs098
        x5, x6 = upper[4], upper[5]
        optimum = [(b[0] - 623.4 * x5 - 1495.5 * x6 + 24300.0 * x5 * x6) / 17.1, 0.0, 0.0, 0.0, x5, x6]

    def f(x):
        return 4.3 * x[0] + 31.8 * x[1] + 63.3 * x[2] + 15.8 * x[3] + 68.5 * x[4] + 4.7 * x[5]

    return Published(
        name,
        f,
        [(0.0, u) for u in upper],
        [0.0] * 6,
        optimum,
        f(optimum),
        g=[lambda x, ci=ci, bi=bi: ci(x) - bi for ci, bi in zip(c, b)],
    )


HOCK_SCHITTKOWSKI = [
    Published("hs001", rosenbrock, [(-BOX, BOX), (-1.5, BOX)], [-2.0, 1.0], [1.0, 1.0], 0.0),
    Published(
        "hs003", lambda x: x[1] + 1e-5 * (x[1] - x[0]) ** 2, [(-BOX, BOX), (0.0, BOX)], [10.0, 1.0], [0.0, 0.0], 0.0
    ),
    Published(
        "hs004",
        lambda x: (x[0] + 1.0) ** 3 / 3.0 + x[1],
        [(1.0, BOX), (0.0, BOX)],
        [1.125, 0.125],
        [1.0, 0.0],
        8.0 / 3.0,
    ),
    Published(
        "hs005",
        lambda x: jnp.sin(x[0] + x[1]) + (x[0] - x[1]) ** 2 - 1.5 * x[0] + 2.5 * x[1] + 1.0,
        [(-1.5, 4.0), (-3.0, 3.0)],
        [0.0, 0.0],
        [0.5 - math.pi / 3.0, -0.5 - math.pi / 3.0],
        -math.sqrt(3.0) / 2.0 - math.pi / 3.0,
    ),
    Published(
        "hs006",
        lambda x: (1.0 - x[0]) ** 2,
        [(-10.0, 10.0), (-10.0, 10.0)],
        [-1.2, 1.0],
        [1.0, 1.0],
        0.0,
        h=[lambda x: 10.0 * (x[1] - x[0] ** 2)],
    ),
    Published(
        "hs007",
        lambda x: jnp.log(1.0 + x[0] ** 2) - x[1],
        [(-10.0, 10.0), (-10.0, 10.0)],
        [2.0, 2.0],
        [0.0, math.sqrt(3.0)],
        -math.sqrt(3.0),
        h=[lambda x: (1.0 + x[0] ** 2) ** 2 + x[1] ** 2 - 4.0],
    ),
    Published(
        "hs009",
        lambda x: jnp.sin(math.pi * x[0] / 12.0) * jnp.cos(math.pi * x[1] / 16.0),
        [(-10.0, 10.0), (-10.0, 10.0)],
        [0.0, 0.0],
        [-3.0, -4.0],
        -0.5,
        h=[lambda x: 4.0 * x[0] - 3.0 * x[1]],
    ),
    Published(
        "hs010",
        lambda x: x[0] - x[1],
        [(-BOX, BOX), (-BOX, BOX)],
        [-10.0, 10.0],
        [0.0, 1.0],
        -1.0,
        g=[lambda x: -3.0 * x[0] ** 2 + 2.0 * x[0] * x[1] - x[1] ** 2 + 1.0],
    ),
    Published(
        "hs011",
        lambda x: (x[0] - 5.0) ** 2 + x[1] ** 2 - 25.0,
        [(-BOX, BOX), (-BOX, BOX)],
        [4.9, 0.1],
        [HS011_X1, HS011_X1**2],
        (HS011_X1 - 5.0) ** 2 + HS011_X1**4 - 25.0,
        g=[lambda x: -(x[0] ** 2) + x[1]],
    ),
    Published(
        "hs012",
        lambda x: 0.5 * x[0] ** 2 + x[1] ** 2 - x[0] * x[1] - 7.0 * x[0] - 7.0 * x[1],
        [(-BOX, BOX), (-BOX, BOX)],
        [0.0, 0.0],
        [2.0, 3.0],
        -30.0,
        g=[lambda x: 25.0 - 4.0 * x[0] ** 2 - x[1] ** 2],
    ),
    Published(
        "hs014",
        lambda x: (x[0] - 2.0) ** 2 + (x[1] - 1.0) ** 2,
        [(-BOX, BOX), (-BOX, BOX)],
        [2.0, 2.0],
        [0.5 * (SQRT7 - 1.0), 0.25 * (SQRT7 + 1.0)],
        9.0 - 23.0 * SQRT7 / 8.0,
        g=[lambda x: -0.25 * x[0] ** 2 - x[1] ** 2 + 1.0],
        h=[lambda x: x[0] - 2.0 * x[1] + 1.0],
    ),
    Published(
        "hs015",
        rosenbrock,
        [(-BOX, 0.5), (-BOX, BOX)],
        [-2.0, 1.0],
        [0.5, 2.0],
        306.5,
        g=[lambda x: x[0] * x[1] - 1.0, lambda x: x[0] + x[1] ** 2],
    ),
    Published(
        "hs021",
        lambda x: 0.01 * x[0] ** 2 + x[1] ** 2 - 100.0,
        [(2.0, 50.0), (-50.0, 50.0)],
        [-1.0, -1.0],
        [2.0, 0.0],
        -99.96,
        g=[lambda x: 10.0 * x[0] - x[1] - 10.0],
    ),
    Published(
        "hs028",
        lambda x: (x[0] + x[1]) ** 2 + (x[1] + x[2]) ** 2,
        [(-BOX, BOX)] * 3,
        [-4.0, 1.0, 1.0],
        [0.5, -0.5, 0.5],
        0.0,
        h=[lambda x: x[0] + 2.0 * x[1] + 3.0 * x[2] - 1.0],
    ),
    Published(
        "hs035",
        lambda x: (
            9.0
            - 8.0 * x[0]
            - 6.0 * x[1]
            - 4.0 * x[2]
            + 2.0 * x[0] ** 2
            + 2.0 * x[1] ** 2
            + x[2] ** 2
            + 2.0 * x[0] * x[1]
            + 2.0 * x[0] * x[2]
        ),
        [(0.0, BOX)] * 3,
        [0.5, 0.5, 0.5],
        [4.0 / 3.0, 7.0 / 9.0, 4.0 / 9.0],
        1.0 / 9.0,
        g=[lambda x: 3.0 - x[0] - x[1] - 2.0 * x[2]],
    ),
    Published(
        "hs038",
        lambda x: (
            100.0 * (x[1] - x[0] ** 2) ** 2
            + (1.0 - x[0]) ** 2
            + 90.0 * (x[3] - x[2] ** 2) ** 2
            + (1.0 - x[2]) ** 2
            + 10.1 * ((x[1] - 1.0) ** 2 + (x[3] - 1.0) ** 2)
            + 19.8 * (x[1] - 1.0) * (x[3] - 1.0)
        ),
        [(-10.0, 10.0)] * 4,
        [-3.0, -1.0, -3.0, -1.0],
        [1.0, 1.0, 1.0, 1.0],
        0.0,
    ),
    Published(
        "hs048",
        lambda x: (x[0] - 1.0) ** 2 + (x[1] - x[2]) ** 2 + (x[3] - x[4]) ** 2,
        [(-BOX, BOX)] * 5,
        [3.0, 5.0, -3.0, 2.0, -2.0],
        [1.0] * 5,
        0.0,
        h=[lambda x: x[0] + x[1] + x[2] + x[3] + x[4] - 5.0, lambda x: x[2] - 2.0 * (x[3] + x[4]) + 3.0],
    ),
    Published(
        "hs046",
        lambda x: (x[0] - x[1]) ** 2 + (x[2] - 1.0) ** 2 + (x[3] - 1.0) ** 4 + (x[4] - 1.0) ** 6,
        [(-BOX, BOX)] * 5,
        [0.5 * SQRT2, 1.75, 0.5, 2.0, 2.0],
        [1.0] * 5,
        0.0,
        h=[
            lambda x: x[0] ** 2 * x[3] + jnp.sin(x[3] - x[4]) - 1.0,
            lambda x: x[1] + x[2] ** 4 * x[3] ** 2 - 2.0,
        ],
    ),
    Published(
        "hs047",
        lambda x: (x[0] - x[1]) ** 2 + (x[1] - x[2]) ** 3 + (x[2] - x[3]) ** 4 + (x[3] - x[4]) ** 4,
        [(-BOX, BOX)] * 5,
        [2.0, SQRT2, -1.0, 2.0 - SQRT2, 0.5],
        [1.0] * 5,
        0.0,
        h=[
            lambda x: x[0] + x[1] ** 2 + x[2] ** 3 - 3.0,
            lambda x: x[1] - x[2] ** 2 + x[3] - 1.0,
            lambda x: x[0] * x[4] - 1.0,
        ],
    ),
    Published(
        "hs008",
        lambda x: 0.0 * x[0] - 1.0,
        [(-BOX, BOX)] * 2,
        [2.0, 1.0],
        [0.5 * (math.sqrt(43.0) + SQRT7), 0.5 * (math.sqrt(43.0) - SQRT7)],
        -1.0,
        h=[lambda x: x[0] ** 2 + x[1] ** 2 - 25.0, lambda x: x[0] * x[1] - 9.0],
    ),
    Published(
        "hs018",
        lambda x: 0.01 * x[0] ** 2 + x[1] ** 2,
        [(2.0, 50.0), (0.0, 50.0)],
        [2.0, 2.0],
        [math.sqrt(250.0), math.sqrt(2.5)],
        5.0,
        g=[lambda x: x[0] * x[1] - 25.0, lambda x: x[0] ** 2 + x[1] ** 2 - 25.0],
    ),
    Published(
        "hs022",
        lambda x: (x[0] - 2.0) ** 2 + (x[1] - 1.0) ** 2,
        [(-BOX, BOX)] * 2,
        [2.0, 2.0],
        [1.0, 1.0],
        1.0,
        g=[lambda x: 2.0 - x[0] - x[1], lambda x: x[1] - x[0] ** 2],
    ),
    Published(
        "hs023",
        lambda x: x[0] ** 2 + x[1] ** 2,
        [(-50.0, 50.0)] * 2,
        [3.0, 1.0],
        [1.0, 1.0],
        2.0,
        g=[
            lambda x: x[0] + x[1] - 1.0,
            lambda x: x[0] ** 2 + x[1] ** 2 - 1.0,
            lambda x: 9.0 * x[0] ** 2 + x[1] ** 2 - 9.0,
            lambda x: x[0] ** 2 - x[1],
            lambda x: x[1] ** 2 - x[0],
        ],
    ),
    Published(
        "hs024",
        lambda x: ((x[0] - 3.0) ** 2 - 9.0) * x[1] ** 3 / (27.0 * SQRT3),
        [(0.0, BOX)] * 2,
        [1.0, 0.5],
        [3.0, SQRT3],
        -1.0,
        g=[lambda x: x[0] / SQRT3 - x[1], lambda x: x[0] + SQRT3 * x[1], lambda x: 6.0 - x[0] - SQRT3 * x[1]],
    ),
    Published(
        "hs026",
        lambda x: (x[0] - x[1]) ** 2 + (x[1] - x[2]) ** 4,
        [(-BOX, BOX)] * 3,
        [-2.6, 2.0, 2.0],
        [1.0, 1.0, 1.0],
        0.0,
        h=[lambda x: (1.0 + x[1] ** 2) * x[0] + x[2] ** 4 - 3.0],
    ),
    Published(
        "hs027",
        lambda x: 0.01 * (x[0] - 1.0) ** 2 + (x[1] - x[0] ** 2) ** 2,
        [(-BOX, BOX)] * 3,
        [2.0, 2.0, 2.0],
        [-1.0, 1.0, 0.0],
        0.04,
        h=[lambda x: x[0] + x[2] ** 2 + 1.0],
    ),
    Published(
        "hs029",
        lambda x: -x[0] * x[1] * x[2],
        [(-BOX, BOX)] * 3,
        [1.0, 1.0, 1.0],
        [4.0, 2.0 * SQRT2, 2.0],
        -16.0 * SQRT2,
        g=[lambda x: 48.0 - x[0] ** 2 - 2.0 * x[1] ** 2 - 4.0 * x[2] ** 2],
    ),
    Published(
        "hs032",
        lambda x: (x[0] + 3.0 * x[1] + x[2]) ** 2 + 4.0 * (x[0] - x[1]) ** 2,
        [(0.0, BOX)] * 3,
        [0.1, 0.7, 0.2],
        [0.0, 0.0, 1.0],
        1.0,
        g=[lambda x: 6.0 * x[1] + 4.0 * x[2] - x[0] ** 3 - 3.0],
        h=[lambda x: 1.0 - x[0] - x[1] - x[2]],
    ),
    Published(
        "hs033",
        lambda x: (x[0] - 1.0) * (x[0] - 2.0) * (x[0] - 3.0) + x[2],
        [(0.0, BOX), (0.0, BOX), (0.0, 5.0)],
        [0.0, 0.0, 3.0],
        [0.0, SQRT2, SQRT2],
        SQRT2 - 6.0,
        g=[lambda x: x[2] ** 2 - x[0] ** 2 - x[1] ** 2, lambda x: x[0] ** 2 + x[1] ** 2 + x[2] ** 2 - 4.0],
    ),
    Published(
        "hs034",
        lambda x: -x[0],
        [(0.0, 100.0), (0.0, 100.0), (0.0, 10.0)],
        [0.0, 1.05, 2.9],
        [math.log(math.log(10.0)), math.log(10.0), 10.0],
        -math.log(math.log(10.0)),
        g=[lambda x: x[1] - jnp.exp(x[0]), lambda x: x[2] - jnp.exp(x[1])],
    ),
    Published(
        "hs039",
        lambda x: -x[0],
        [(-BOX, BOX)] * 4,
        [2.0] * 4,
        [1.0, 1.0, 0.0, 0.0],
        -1.0,
        h=[lambda x: x[1] - x[0] ** 3 - x[2] ** 2, lambda x: x[0] ** 2 - x[1] - x[3] ** 2],
    ),
    Published(
        "hs040",
        lambda x: -x[0] * x[1] * x[2] * x[3],
        [(-BOX, BOX)] * 4,
        [0.8] * 4,
        [2.0 ** (-1.0 / 3.0), 2.0 ** (-0.5), 2.0 ** (-11.0 / 12.0), 2.0 ** (-0.25)],
        -0.25,
        h=[lambda x: x[0] ** 3 + x[1] ** 2 - 1.0, lambda x: x[0] ** 2 * x[3] - x[2], lambda x: x[3] ** 2 - x[1]],
    ),
    Published(
        "hs043",
        lambda x: (
            x[0] ** 2 + x[1] ** 2 + 2.0 * x[2] ** 2 + x[3] ** 2 - 5.0 * x[0] - 5.0 * x[1] - 21.0 * x[2] + 7.0 * x[3]
        ),
        [(-BOX, BOX)] * 4,
        [0.0] * 4,
        [0.0, 1.0, 2.0, -1.0],
        -44.0,
        g=[
            lambda x: 8.0 - x[0] ** 2 - x[1] ** 2 - x[2] ** 2 - x[3] ** 2 - x[0] + x[1] - x[2] + x[3],
            lambda x: 10.0 - x[0] ** 2 - 2.0 * x[1] ** 2 - x[2] ** 2 - 2.0 * x[3] ** 2 + x[0] + x[3],
            lambda x: 5.0 - 2.0 * x[0] ** 2 - x[1] ** 2 - x[2] ** 2 - 2.0 * x[0] + x[1] + x[3],
        ],
    ),
    Published(
        "hs044",
        lambda x: x[0] - x[1] - x[2] - x[0] * x[2] + x[0] * x[3] + x[1] * x[2] - x[1] * x[3],
        [(0.0, BOX)] * 4,
        [0.0] * 4,
        [0.0, 3.0, 0.0, 4.0],
        -15.0,
        g=[
            lambda x: 8.0 - x[0] - 2.0 * x[1],
            lambda x: 12.0 - 4.0 * x[0] - x[1],
            lambda x: 12.0 - 3.0 * x[0] - 4.0 * x[1],
            lambda x: 8.0 - 2.0 * x[2] - x[3],
            lambda x: 8.0 - x[2] - 2.0 * x[3],
            lambda x: 5.0 - x[2] - x[3],
        ],
    ),
    Published(
        "hs045",
        lambda x: 2.0 - x[0] * x[1] * x[2] * x[3] * x[4] / 120.0,
        [(0.0, float(i)) for i in range(1, 6)],
        [2.0] * 5,
        [1.0, 2.0, 3.0, 4.0, 5.0],
        1.0,
    ),
    Published(
        "hs052",
        lambda x: (4.0 * x[0] - x[1]) ** 2 + (x[1] + x[2] - 2.0) ** 2 + (x[3] - 1.0) ** 2 + (x[4] - 1.0) ** 2,
        [(-BOX, BOX)] * 5,
        [2.0] * 5,
        [-33.0 / 349.0, 11.0 / 349.0, 180.0 / 349.0, -158.0 / 349.0, 11.0 / 349.0],
        1859.0 / 349.0,
        h=[lambda x: x[0] + 3.0 * x[1], lambda x: x[2] + x[3] - 2.0 * x[4], lambda x: x[1] - x[4]],
    ),
    Published(
        "hs071",
        lambda x: x[0] * x[3] * (x[0] + x[1] + x[2]) + x[2],
        [(1.0, 5.0)] * 4,
        [1.0, 5.0, 5.0, 1.0],
        [1.0, 4.742999637, 3.821149984, 1.379408293],
        17.0140173,
        g=[lambda x: x[0] * x[1] * x[2] * x[3] - 25.0],
        h=[lambda x: x[0] ** 2 + x[1] ** 2 + x[2] ** 2 + x[3] ** 2 - 40.0],
    ),
    Published(
        "hs076",
        lambda x: (
            x[0] ** 2
            + 0.5 * x[1] ** 2
            + x[2] ** 2
            + 0.5 * x[3] ** 2
            - x[0] * x[2]
            + x[2] * x[3]
            - x[0]
            - 3.0 * x[1]
            + x[2]
            - x[3]
        ),
        [(0.0, BOX)] * 4,
        [0.5] * 4,
        [3.0 / 11.0, 23.0 / 11.0, 0.0, 6.0 / 11.0],
        -4.681818181818,
        g=[
            lambda x: 5.0 - x[0] - 2.0 * x[1] - x[2] - x[3],
            lambda x: 4.0 - 3.0 * x[0] - x[1] - 2.0 * x[2] + x[3],
            lambda x: x[1] + 4.0 * x[2] - 1.5,
        ],
    ),
    Published(
        "hs019",
        lambda x: (x[0] - 10.0) ** 3 + (x[1] - 20.0) ** 3,
        [(13.0, 100.0), (0.0, 100.0)],
        [20.1, 5.84],
        [14.095, HS019_X2],
        (14.095 - 10.0) ** 3 + (HS019_X2 - 20.0) ** 3,
        g=[
            lambda x: (x[0] - 5.0) ** 2 + (x[1] - 5.0) ** 2 - 100.0,
            lambda x: 82.81 - (x[1] - 5.0) ** 2 - (x[0] - 6.0) ** 2,
        ],
    ),
    Published(
        "hs030",
        lambda x: x[0] ** 2 + x[1] ** 2 + x[2] ** 2,
        [(1.0, 10.0), (-10.0, 10.0), (-10.0, 10.0)],
        [1.0] * 3,
        [1.0, 0.0, 0.0],
        1.0,
        g=[lambda x: x[0] ** 2 + x[1] ** 2 - 1.0],
    ),
    Published(
        "hs036",
        lambda x: -x[0] * x[1] * x[2],
        [(0.0, 20.0), (0.0, 11.0), (0.0, 42.0)],
        [10.0] * 3,
        [20.0, 11.0, 15.0],
        -3300.0,
        g=[lambda x: 72.0 - x[0] - 2.0 * x[1] - 2.0 * x[2]],
    ),
    Published(
        "hs037",
        lambda x: -x[0] * x[1] * x[2],
        [(0.0, 42.0)] * 3,
        [10.0] * 3,
        [24.0, 12.0, 12.0],
        -3456.0,
        g=[lambda x: 72.0 - x[0] - 2.0 * x[1] - 2.0 * x[2], lambda x: x[0] + 2.0 * x[1] + 2.0 * x[2]],
    ),
    Published(
        "hs041",
        lambda x: 2.0 - x[0] * x[1] * x[2],
        [(0.0, 1.0)] * 3 + [(0.0, 2.0)],
        [2.0] * 4,
        [2.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0, 2.0],
        52.0 / 27.0,
        h=[lambda x: x[0] + 2.0 * x[1] + 2.0 * x[2] - x[3]],
    ),
    Published(
        "hs042",
        lambda x: (x[0] - 1.0) ** 2 + (x[1] - 2.0) ** 2 + (x[2] - 3.0) ** 2 + (x[3] - 4.0) ** 2,
        [(-BOX, BOX)] * 4,
        [1.0] * 4,
        [2.0, 2.0, 0.6 * SQRT2, 0.8 * SQRT2],
        28.0 - 10.0 * SQRT2,
        h=[lambda x: x[0] - 2.0, lambda x: x[2] ** 2 + x[3] ** 2 - 2.0],
    ),
    Published(
        "hs050",
        lambda x: (x[0] - x[1]) ** 2 + (x[1] - x[2]) ** 2 + (x[2] - x[3]) ** 4 + (x[3] - x[4]) ** 2,
        [(-BOX, BOX)] * 5,
        [35.0, -31.0, 11.0, 5.0, -5.0],
        [1.0] * 5,
        0.0,
        h=[
            lambda x: x[0] + 2.0 * x[1] + 3.0 * x[2] - 6.0,
            lambda x: x[1] + 2.0 * x[2] + 3.0 * x[3] - 6.0,
            lambda x: x[2] + 2.0 * x[3] + 3.0 * x[4] - 6.0,
        ],
    ),
    Published(
        "hs051",
        lambda x: (x[0] - x[1]) ** 2 + (x[1] + x[2] - 2.0) ** 2 + (x[3] - 1.0) ** 2 + (x[4] - 1.0) ** 2,
        [(-BOX, BOX)] * 5,
        [2.5, 0.5, 2.0, -1.0, 0.5],
        [1.0] * 5,
        0.0,
        h=[lambda x: x[0] + 3.0 * x[1] - 4.0, lambda x: x[2] + x[3] - 2.0 * x[4], lambda x: x[1] - x[4]],
    ),
    # hs056's optimum: sin^2 x4 = 2.4 / 4.2, sin^2 x5 = sin^2 x6 = 1.2 / 4.2, x7 = pi / 2
    # (h1 to h4 with the book's x1, x2, x3), f* = -2.4 * 1.2 * 1.2.
    Published(
        "hs056",
        lambda x: -x[0] * x[1] * x[2],
        [(-BOX, BOX)] * 7,
        [1.0, 1.0, 1.0] + [math.asin(math.sqrt(1.0 / 4.2))] * 3 + [math.asin(math.sqrt(5.0 / 7.2))],
        [2.4, 1.2, 1.2, math.asin(math.sqrt(4.0 / 7.0))] + [math.asin(math.sqrt(2.0 / 7.0))] * 2 + [math.pi / 2.0],
        -3.456,
        h=[
            lambda x: x[0] - 4.2 * jnp.sin(x[3]) ** 2,
            lambda x: x[1] - 4.2 * jnp.sin(x[4]) ** 2,
            lambda x: x[2] - 4.2 * jnp.sin(x[5]) ** 2,
            lambda x: x[0] + 2.0 * x[1] + 2.0 * x[2] - 7.2 * jnp.sin(x[6]) ** 2,
        ],
    ),
    # hs063 and hs072: x* and f* are the book's optima polished by Newton's method on the
    # KKT equations of their active set (both rows) at 40 digits (mpmath, independent of
    # magdesign); the published 12-digit x* of hs072 lie 2e-6 (relative) from that point.
    Published(
        "hs063",
        lambda x: 1000.0 - x[0] ** 2 - 2.0 * x[1] ** 2 - x[2] ** 2 - x[0] * x[1] - x[0] * x[2],
        [(0.0, BOX)] * 3,
        [2.0] * 3,
        [3.5121213418747199, 0.21698794151522303, 3.552171154827017],
        961.71517213005217,
        h=[lambda x: 8.0 * x[0] + 14.0 * x[1] + 7.0 * x[2] - 56.0, lambda x: x[0] ** 2 + x[1] ** 2 + x[2] ** 2 - 25.0],
    ),
    Published(
        "hs072",
        lambda x: 1.0 + x[0] + x[1] + x[2] + x[3],
        [(1e-3, (4.0 - i) * 1e5) for i in range(4)],
        [1.0] * 4,
        [193.40742727194631, 179.54707603227455, 185.01806335815153, 168.70679112724058],
        727.67935778961297,
        g=[
            lambda x: 0.0401 - 4.0 / x[0] - 2.25 / x[1] - 1.0 / x[2] - 0.25 / x[3],
            lambda x: 0.010085 - 0.16 / x[0] - 0.36 / x[1] - 0.64 / x[2] - 0.64 / x[3],
        ],
    ),
    # hs057 and hs069: the optima of Schittkowski's validated transcription (PROB.FOR, 2011),
    # 12 digits; the solver before them ended both "max_steps_reached".
    Published(
        "hs057",
        lambda x: jnp.sum(
            (jnp.asarray(HS057_B) - x[0] - (0.49 - x[0]) * jnp.exp(-x[1] * (jnp.asarray(HS057_A) - 8.0))) ** 2
        ),
        [(0.4, BOX), (-4.0, BOX)],
        [0.42, 5.0],
        [0.419952674511, 1.28484562930],
        0.0284596697213,
        g=[lambda x: 0.49 * x[1] - x[0] * x[1] - 0.09],
    ),
    Published(
        "hs069",
        lambda x: (0.4 - x[3] * (1000.0 * jnp.expm1(x[0]) - x[2]) / (jnp.expm1(x[0]) + x[3])) / x[0],
        [(1e-4, 100.0), (0.0, 100.0), (0.0, 2.0), (0.0, 2.0)],
        [1.0] * 4,
        [0.0293714180830, 1.19025343488, 0.233946796758, 0.791667815694],
        -956.712887064,
        h=[
            lambda x: x[2] - 2.0 * ndtr(-x[1]),
            lambda x: x[3] - ndtr(2.0 - x[1]) - ndtr(-2.0 - x[1]),
        ],
    ),
    # hs097 and hs098 ended "successful" at another vertex from their (infeasible) start
    # (f = 4.0712) until the QP took the floor off along the limits it holds
    hs095_family("hs095", [4.97, -1.88, -29.08, -78.02]),
    hs095_family("hs096", [4.97, -1.88, -69.08, -118.02]),
    hs095_family("hs097", [32.97, 25.12, -29.08, -78.02]),
    hs095_family("hs098", [32.97, 25.12, -124.08, -173.02]),
    # hs116 (a three-stage membrane separation) ended "max_steps_reached" 1e-5 (relative) above
    # f*: at its optimum the 11 active limits and 2 active bounds have rank 12 in 13
    # variables, and the QP's Hessian, made definite as a whole, gave the one free direction
    # a curvature where the Lagrangian has none (SQP.dependent_met). The book's f* =
    # 97.588409 is 1e-5 (relative) above the local minimum next to its x*; x* and f* here are
    # that minimum, found from the book's x* by scipy's SLSQP and then Newton's method on the
    # KKT equations of its active set (scipy.optimize.root; a scratch check, independent of
    # magdesign).
    Published(
        "hs116",
        lambda x: x[10] + x[11] + x[12],
        [
            (0.1, 1.0),
            (0.1, 1.0),
            (0.1, 1.0),
            (1e-4, 0.1),
            (0.1, 0.9),
            (0.1, 0.9),
            (0.1, 1000.0),
            (0.1, 1000.0),
            (500.0, 1000.0),
            (0.1, 500.0),
            (1.0, 150.0),
            (1e-4, 150.0),
            (1e-4, 150.0),
        ],
        [0.5, 0.8, 0.9, 0.1, 0.14, 0.5, 489.0, 80.0, 650.0, 450.0, 150.0, 150.0, 150.0],
        [
            0.8037731573766543,
            0.8999858006730379,
            0.9709824354838092,
            0.1,
            0.19081317621550714,
            0.46065478285226075,
            574.0775735827623,
            74.07757358276244,
            500.0161601689685,
            0.1,
            20.2330906973676,
            77.34768992730736,
            0.006728933395573754,
        ],
        97.58750955807054,
        g=[
            lambda x: x[2] - x[1],
            lambda x: x[1] - x[0],
            lambda x: 1.0 - 0.002 * x[6] + 0.002 * x[7],
            lambda x: x[10] + x[11] + x[12] - 50.0,
            lambda x: x[12] - 1.262626 * x[9] + 1.231059 * x[2] * x[9],
            lambda x: x[4] - 0.03475 * x[1] - 0.975 * x[1] * x[4] + 0.00975 * x[1] ** 2,
            lambda x: x[5] - 0.03475 * x[2] - 0.975 * x[2] * x[5] + 0.00975 * x[2] ** 2,
            lambda x: x[3] - 0.03475 * x[0] - 0.975 * x[0] * x[3] + 0.00975 * x[0] ** 2,
            lambda x: x[11] - 1.262626 * x[8] + 1.231059 * x[1] * x[8],
            lambda x: x[10] - 1.262626 * x[7] + 1.231059 * x[0] * x[7],
            lambda x: x[4] * x[6] - x[0] * x[7] - x[3] * x[6] + x[3] * x[7],
            lambda x: 1.0 - 0.002 * (x[1] * x[8] + x[4] * x[7] - x[0] * x[7] - x[5] * x[8]) - x[4] - x[5],
            lambda x: x[1] * x[8] - x[2] * x[9] - x[5] * x[8] - 500.0 * x[1] + 500.0 * x[5] + x[1] * x[9],
            lambda x: x[1] - 0.9 - 0.002 * (x[1] * x[9] - x[2] * x[9]),
            lambda x: 250.0 - x[10] - x[11] - x[12],
        ],
    ),
]
