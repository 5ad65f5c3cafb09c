"""Mechanics: materials, elastomer layers (stiffness, displacement field) and domes (SI: m, N, Pa)."""

from magdesign.mechanics.dome import ComplianceEstimate as ComplianceEstimate
from magdesign.mechanics.dome import DomeCurve as DomeCurve
from magdesign.mechanics.dome import DomeResult as DomeResult
from magdesign.mechanics.dome import dome_compliance as dome_compliance
from magdesign.mechanics.dome import dome_curve as dome_curve
from magdesign.mechanics.finite_layer import LayerPress as LayerPress
from magdesign.mechanics.finite_layer import press_displacement as press_displacement
from magdesign.mechanics.finite_layer import press_layer as press_layer
from magdesign.mechanics.layer import LayerStiffness as LayerStiffness
from magdesign.mechanics.layer import compression_modulus as compression_modulus
from magdesign.mechanics.layer import layer_stiffness as layer_stiffness
from magdesign.mechanics.layer import shape_factor as shape_factor
from magdesign.mechanics.materials import AbstractHyperelastic as AbstractHyperelastic
from magdesign.mechanics.materials import AbstractMaterial as AbstractMaterial
from magdesign.mechanics.materials import LinearElastic as LinearElastic
from magdesign.mechanics.materials import MooneyRivlin as MooneyRivlin
from magdesign.mechanics.materials import NeoHookean as NeoHookean
from magdesign.mechanics.skin_layer import ElasticLayer as ElasticLayer
from magdesign.mechanics.skin_layer import HertzContact as HertzContact
from magdesign.mechanics.skin_layer import SurfaceLoad as SurfaceLoad
from magdesign.mechanics.skin_layer import hertz_contact as hertz_contact
from magdesign.mechanics.skin_layer import layer_displacement as layer_displacement
from magdesign.mechanics.skin_layer import thin_layer_contact as thin_layer_contact
from magdesign.mechanics.viscoelastic import lag_filter as lag_filter
from magdesign.mechanics.viscoelastic import lag_pole as lag_pole
from magdesign.mechanics.viscoelastic import time_constant_from_pole as time_constant_from_pole
