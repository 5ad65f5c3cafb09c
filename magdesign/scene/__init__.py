"""Scenes: a sensor's forward chain, with exactly the effects it lists.

Example::

    spec = tomllib.load(open("examples/dome_hall.toml", "rb"))
    scene = scene_from_spec(spec)
    result = simulate(scene, loads_from_spec(spec))
    print(simulation_table(result))
"""

from magdesign.scene.core import MECHANICS_CONVERGED as MECHANICS_CONVERGED
from magdesign.scene.core import AbstractScene as AbstractScene
from magdesign.scene.core import SimulationResult as SimulationResult
from magdesign.scene.core import outputs as outputs
from magdesign.scene.core import parameters as parameters
from magdesign.scene.core import simulate as simulate
from magdesign.scene.core import simulation_json as simulation_json
from magdesign.scene.core import simulation_table as simulation_table
from magdesign.scene.core import with_parameters as with_parameters
from magdesign.scene.effects import EFFECT_NAMES as EFFECT_NAMES
from magdesign.scene.film_scene import FilmScene as FilmScene
from magdesign.scene.interop import MagpylibObjects as MagpylibObjects
from magdesign.scene.interop import to_magpylib as to_magpylib
from magdesign.scene.loads import Loads as Loads
from magdesign.scene.loads import loads_from_spec as loads_from_spec
from magdesign.scene.magnet_scene import MagnetScene as MagnetScene
from magdesign.scene.pole_scene import PoleScene as PoleScene


def __getattr__(name):
    # scene_from_spec is the spec language's (magdesign.spec.scene), which builds scenes from
    # this package's modules: it loads on first use, so that either package imports first
    if name == "scene_from_spec":
        from magdesign.spec.scene import scene_from_spec

        return scene_from_spec
    raise AttributeError(f"module 'magdesign.scene' has no attribute {name!r}")


def __dir__():
    return sorted({*globals(), "scene_from_spec"})
