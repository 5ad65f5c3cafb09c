"""Generate cuboid.json: 50-digit values of the field of a uniformly magnetised cuboid.

Run by hand (a few seconds; needs mpmath, e.g. the system Python):
    python3 tests/fields/references/make_cuboid_references.py

Independent of magdesign's numerics: the textbook closed form (surface charges summed
over the 8 corners, as written, with no rewriting for stability) evaluated in 50-digit
arithmetic, which absorbs its cancellations (far away the terms cancel to r^-3, a
1e3 x size point loses about 12 digits, a 1e-6 flat block 6 more). With half sides
(a, b, c), u = x -+ a, v = y -+ b, w = z -+ c (sign s = +1 for the + corners) and
R = |(u, v, w)|, B = chi J - S J with

    4 pi S_xx = sum s atan(v w / (u R)),   4 pi S_xy = -sum s ln(w + R)  (and cyclic),

chi = 1 inside. Points are kept off the faces' planes (where the atan is 0 / 0).
Lengths are in units of the half diagonal, fields in units of the polarization; for
each point the field of a unit polarization along x, y and z.
"""

import json
import random
from pathlib import Path

import mpmath as mp

mp.mp.dps = 50

# full sides, in any unit (the references are scaled to the half diagonal)
SHAPES = {
    "2x3x1": (2, 3, 1),
    "cube": (1, 1, 1),
    "flat_1e-6": (1, 1.5, 1e-6),
    "flat_1e-3": (1e-3, 1, 0.7),
    "long_1e3": (1, 1e3, 1.3),
    "rod_1e-3": (1e-3, 2e-3, 1),
}


def tensor(point, half):
    x, y, z = (mp.mpf(v) for v in point)  # float64 values, taken exactly
    a, b, c = (mp.mpf(v) for v in half)
    S = [[mp.mpf(0)] * 3 for _ in range(3)]
    for su in (1, -1):
        for sv in (1, -1):
            for sw in (1, -1):
                u, v, w = x + su * a, y + sv * b, z + sw * c
                R = mp.sqrt(u * u + v * v + w * w)
                s = su * sv * sw
                S[0][0] += s * mp.atan(v * w / (u * R))
                S[1][1] += s * mp.atan(u * w / (v * R))
                S[2][2] += s * mp.atan(u * v / (w * R))
                S[0][1] -= s * mp.log(w + R)
                S[0][2] -= s * mp.log(v + R)
                S[1][2] -= s * mp.log(u + R)
    S[1][0], S[2][0], S[2][1] = S[0][1], S[0][2], S[1][2]
    return [[S[i][k] / (4 * mp.pi) for k in range(3)] for i in range(3)]


def fields(point, half):
    S = tensor(point, half)
    inside = all(abs(mp.mpf(p)) < mp.mpf(h) for p, h in zip(point, half))
    return [[(1 if (inside and i == k) else 0) - S[i][k] for i in range(3)] for k in range(3)]


def points(half, rng):
    """Inside, near (0.7 - 3 half diagonals), 1e-9 off a face, 1e-6 off an edge and a
    corner, around the far-field switch (20) and far away (100, 1000)."""
    a, b, c = half
    out = [(0.3 * a, -0.2 * b, 0.6 * c), (0.95 * a, 0.9 * b, -0.99 * c)]
    for radius in (0.7, 1.5, 3.0, 8.0, 19.9, 20.1, 100.0, 1000.0):
        for _ in range(3):
            d = [rng.gauss(0, 1) for _ in range(3)]
            n = sum(v * v for v in d) ** 0.5
            out.append(tuple(radius * v / n for v in d))
    out += [
        (a * (1 + 1e-9), 0.3 * b, -0.2 * c),  # beside the x face
        (0.2 * a, -0.4 * b, c * (1 + 1e-9)),  # above the z face
        (0.2 * a, -0.4 * b, c * (1 - 1e-9)),  # just inside it
        (a + 1e-6, b + 1e-6, 0.1 * c),  # beside an edge along z
        (0.3 * a, b + 1e-6, -c - 1e-6),  # beside an edge along x
        (a + 1e-6, -b - 1e-6, c + 1e-6),  # beside a corner
        (a + 2.0, 0.1 * b, 0.05 * c),  # on an edge's extension line
        (0.0001, 0.0002, c + 0.5),  # near the z axis above
    ]
    # in the slab of the shortest side, beside the block, in and out of the faces' extent
    k = min(range(3), key=lambda i: half[i])
    for p in [(1.3, 0.4, 0.5), (1.001, 1.2, -0.3), (0.2, 1.5, 0.9), (3.0, 2.0, 0.1), (0.5, 0.5, 0.2)]:
        point = [p[0] * half[(k + 1) % 3], p[1] * half[(k + 2) % 3], p[2] * half[k]]
        out.append(tuple(point[(i - k - 1) % 3] for i in range(3)))
    return out


def main():
    rng = random.Random(7)
    cases = []
    for name, sides in SHAPES.items():
        half = [mp.mpf(v) / 2 for v in sides]
        diagonal = mp.sqrt(sum(h * h for h in half))
        half = [float(h / diagonal) for h in half]  # the test's float64 sides, exactly
        for point in points(half, rng):
            columns = fields(point, half)
            cases.append(
                {
                    "shape": name,
                    "half_sides": half,
                    "point": [float(v) for v in point],
                    "field_of_x": [mp.nstr(v, 25) for v in columns[0]],
                    "field_of_y": [mp.nstr(v, 25) for v in columns[1]],
                    "field_of_z": [mp.nstr(v, 25) for v in columns[2]],
                }
            )
    path = Path(__file__).parent / "cuboid.json"
    path.write_text(json.dumps({"generator": Path(__file__).name, "dps": mp.mp.dps, "cases": cases}, indent=1) + "\n")


if __name__ == "__main__":
    main()
