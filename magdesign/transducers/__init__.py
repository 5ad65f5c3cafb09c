"""Transducers: Hall, GMR / spin valve and inductor read-outs (SI: T, V, A, Ohm)."""
