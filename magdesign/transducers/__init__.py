"""Transducers: Hall, GMR / spin valve and inductor read-outs (SI: T, V, A, Ohm)."""

from magdesign.frames import rotation_matrix as rotation_matrix
from magdesign.transducers.gmr import SpinValve as SpinValve
from magdesign.transducers.gmr import chip_frame as chip_frame
from magdesign.transducers.gmr import inesc_spin_valve as inesc_spin_valve
from magdesign.transducers.gmr import nve_aa003 as nve_aa003
from magdesign.transducers.gmr import panasonic_meander as panasonic_meander
from magdesign.transducers.gmr import to_chip as to_chip
from magdesign.transducers.hall import Hall3D as Hall3D
from magdesign.transducers.hall import ak8963 as ak8963
from magdesign.transducers.hall import apply_gain_offset as apply_gain_offset
from magdesign.transducers.hall import mlx90393 as mlx90393
from magdesign.transducers.inductor import count_events as count_events
from magdesign.transducers.inductor import emf as emf
from magdesign.transducers.inductor import slip_flags as slip_flags
from magdesign.transducers.resolution import Bound as Bound
from magdesign.transducers.resolution import cramer_rao as cramer_rao
from magdesign.transducers.signal import add_noise as add_noise
from magdesign.transducers.signal import quantise as quantise
from magdesign.transducers.signal import saturate as saturate
from magdesign.transducers.signal import soft_clip as soft_clip
