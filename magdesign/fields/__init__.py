"""Magnetic sources as pure JAX kernels (SI: positions in m, fields in T)."""

from magdesign.fields.film import film as film
from magdesign.fields.film import film_angle as film_angle
from magdesign.fields.film import film_magnitude as film_magnitude
