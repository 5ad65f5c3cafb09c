"""Magnetic sources as pure JAX kernels (SI: positions in m, fields in T).

One convention for every function (docs/models.md, "Conventions"): positions in the
source's own frame, centred on the body; magnetisation as the polarization J = mu0 M
(T, ``polarization=``); round bodies sized by radius (and height along their axis), blocks
by their full sides (``dimension=``).
"""

from magdesign.fields.cuboid import cuboid as cuboid
from magdesign.fields.cuboid import cuboid_tensor as cuboid_tensor
from magdesign.fields.cylinder import cylinder as cylinder
from magdesign.fields.cylinder import cylinder_axial as cylinder_axial
from magdesign.fields.cylinder import cylinder_on_axis as cylinder_on_axis
from magdesign.fields.dipole import dipole as dipole
from magdesign.fields.film import film as film
from magdesign.fields.film import film_angle as film_angle
from magdesign.fields.film import film_magnitude as film_magnitude
