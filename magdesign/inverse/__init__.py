"""From readings back to displacement and force; calibration of a scene's constants."""

from magdesign.inverse.calibration import Calibration as Calibration
from magdesign.inverse.calibration import calibrate as calibrate
from magdesign.inverse.displacement import InverseStatus as InverseStatus
from magdesign.inverse.displacement import Inversion as Inversion
from magdesign.inverse.displacement import displacement_grid as displacement_grid
from magdesign.inverse.displacement import forward_readings as forward_readings
from magdesign.inverse.displacement import invert_displacement as invert_displacement
from magdesign.inverse.film import film_forces as film_forces
