"""Magnetic sources as pure JAX kernels (SI: positions in m, fields in T)."""
