"""The built-in default design (the dome-Hall sensor) written by hand as a plain model:
a test problem for the solver with closed-form answers, and an independent check of the
scene chain that the spec (magdesign/design/default.toml, the one definition) runs.

An N35 magnet (3 mm x 1 mm, Br 1.17 T) under a Mooney-Rivlin dome of outer radius 8 mm,
an AK8963 Hall sensor on its axis. Free: the rest gap between the magnet's top face and
the sensor, and the dome's wall thickness. Target: compliance 0.32 mm/N at 5 N. Limit:
the field at closest approach (rest gap - compliance x 5 N) at most 4.8 mT, the sensor's
saturation. Objective: the largest sensitivity, which makes the limit active.
"""

import equinox as eqx
from jaxtyping import Array, Float

from magdesign.design.problem import Limit, Objective, Problem, Target, Variable
from magdesign.fields import cylinder_axial
from magdesign.mechanics import DomeResult, MooneyRivlin, dome_compliance
from magdesign.scene import MECHANICS_CONVERGED
from magdesign.units import mm, mT


class DomeHallModel(eqx.Module):
    """{gap, thickness} (m) -> compliance (m/N), closest_gap (m), field_closest (T),
    field_rest (T), sensitivity (T/N) of the magnet-in-dome sensor at ``max_force``."""

    radius: float = 1.5 * mm
    height: float = 1.0 * mm
    remanence: float = 1.17
    outer_radius: float = 8.0 * mm
    material: MooneyRivlin = MooneyRivlin(c10=0.1182e6, c01=0.1769e6)
    max_force: float = 5.0
    fidelity: str = eqx.field(static=True, default="reissner")

    def field(self, z):
        return cylinder_axial(z + self.height / 2, radius=self.radius, height=self.height, polarization=self.remanence)

    def __call__(self, values: dict[str, Float[Array, ""]]) -> dict[str, Float[Array, ""]]:
        compliance, result = dome_compliance(
            outer_radius=self.outer_radius,
            thickness=values["thickness"],
            material=self.material,
            max_force=self.max_force,
            fidelity=self.fidelity,
            throw=False,
        )
        closest = values["gap"] - compliance * self.max_force
        field_closest, field_rest = self.field(closest), self.field(values["gap"])
        return {
            "compliance": compliance,
            "closest_gap": closest,
            "field_closest": field_closest,
            "field_rest": field_rest,
            "sensitivity": (field_closest - field_rest) / self.max_force,
            MECHANICS_CONVERGED: (result == DomeResult.successful).astype(float),
        }


def default_problem(fidelity: str = "reissner") -> Problem:
    """The default design; ``fidelity`` is the dome model's ("reissner", "axisymmetric")."""
    return Problem(
        DomeHallModel(fidelity=fidelity),
        [
            Variable("gap", 4.0 * mm, 20.0 * mm, start=10.0 * mm, unit="mm"),
            Variable("thickness", 1.5 * mm, 4.0 * mm, start=2.0 * mm, unit="mm"),
        ],
        [Target("compliance", 0.32 * mm, unit="mm/N")],
        [Limit("field_closest", upper=4.8 * mT, unit="mT")],
        Objective("sensitivity", "max"),
        report=("closest_gap",),
        converged=MECHANICS_CONVERGED,
    )
