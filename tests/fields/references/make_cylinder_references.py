"""Generate cylinder.json: 40-digit values of the field of a uniformly magnetised cylinder.

Run by hand (about 10 minutes): .venv/bin/python tests/fields/references/make_cylinder_references.py

Independent of magdesign: the side wall of a cylinder of radius 1 and half height b
carries, for unit polarization along +z, the surface current phi_hat (B by Biot-Savart)
and, for unit polarization along +x, the surface charge cos(phi') (B = H + J inside).
The integral over the wall's height is done by hand,

    int_{-b}^{b} dz' / (a^2 + (z - z')^2)^(3/2) = [t / (a^2 sqrt(a^2 + t^2))]_{z-b}^{z+b}
    int_{-b}^{b} (z - z') dz' / (a^2 + (z - z')^2)^(3/2) = [-1 / sqrt(a^2 + t^2)]_{z-b}^{z+b}

(a the in-plane distance to the wall point, t = z - z'), the one over its angle by mpmath
(tanh-sinh, split at the point's own angle) at 40 significant digits. Points are in units
of the radius; the field in units of the polarization.
"""

import json
from pathlib import Path

import mpmath as mp

mp.mp.dps = 40

# height / radius: a 1 nm thick disc of 1 mm radius, thin films, the dome-Hall magnet (3 x 1 mm),
# a cube-like one, long rods up to 1000 radii.
ASPECTS = ("1e-6", "1e-3", "0.04", "0.6666666666666666", "2", "20", "1000")


def field(x, y, z, b, direction):
    x, y, z, b = (mp.mpf(v) for v in (x, y, z, b))

    def components(phi):
        c, s = mp.cos(phi), mp.sin(phi)
        a2 = (x - c) ** 2 + (y - s) ** 2
        i0 = (z + b) / (a2 * mp.sqrt(a2 + (z + b) ** 2)) - (z - b) / (a2 * mp.sqrt(a2 + (z - b) ** 2))
        i1 = 1 / mp.sqrt(a2 + (z - b) ** 2) - 1 / mp.sqrt(a2 + (z + b) ** 2)
        if direction == "z":
            return [c * i1, s * i1, (1 - x * c - y * s) * i0]
        return [c * (x - c) * i0, c * (y - s) * i0, c * i1]

    phi0 = mp.atan2(y, x)
    cuts = [phi0 + k * mp.pi / 2 for k in range(5)]
    values = [mp.quad(lambda phi: components(phi)[i], cuts) / (4 * mp.pi) for i in range(3)]
    inside = mp.sqrt(x * x + y * y) < 1 and abs(z) < b
    if direction == "x" and inside:
        values[0] += 1
    return values


def points(b):
    """(x, y, z) in radii: the axis, faces, edges, the wall, near the axis, far away."""
    c, s = 0.7648421872844885, 0.644217687237691  # cos, sin of 0.7 rad
    near = [
        (0, 0, b + 0.01),
        (0, 0, b + 0.3),
        (0, 0, 3.16),
        (0, 0, b + 10),
        (0, 0, 1e3),
        (0.3 * c, 0.3 * s, b + 1e-3),
        (0.5, 0.2, b + 0.7),
        (1 + 1e-9, 0, b),
        (c * (1 + 1e-3), s * (1 + 1e-3), b + 1e-3),
        (1.0, 0, b + 1e-7),
        (1.5 * c, 1.5 * s, 0),
        (1 + 1e-4, 0, 0.5 * b),
        (2.0, 1.0, b + 0.1),
        (1e-4 * c, 1e-4 * s, b + 0.5),
        (0.02, 0, b + 1),
        (0.06 * c, 0.06 * s, -b - 4.7),
        (3.0, 2.0, 1.0),
        (0.6e3, 0, 0.8e3),
        (0.5 * c, 0.5 * s, 0.5 * b),
    ]
    if b > 1:  # long rods: beside the middle, beyond the ends, along the side
        near += [(0.3, 0.2, b + 130), (2 * c, 2 * s, b + 30), (50, 0, 0.5 * b), (1e-3, 0, b + 300), (1.2, 0, 0.9 * b)]
    return [tuple(float(v) for v in p) for p in near]


def main():
    cases = []
    for aspect in ASPECTS:
        b = float(aspect) / 2
        for point in points(b):
            for direction in ("z", "x"):
                values = field(*point, b, direction)
                cases.append(
                    {
                        "height_over_radius": aspect,
                        "point": list(point),
                        "direction": direction,
                        "field": [mp.nstr(v, 25) for v in values],
                    }
                )
        print(aspect, len(cases), flush=True)
    path = Path(__file__).with_name("cylinder.json")
    path.write_text(json.dumps({"generator": Path(__file__).name, "digits": 40, "cases": cases}, indent=1) + "\n")


if __name__ == "__main__":
    main()
