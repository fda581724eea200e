"""The library of candidate effects: one module per effect, each exposing ``EFFECT``.

Adding an effect is adding one module to this package that defines ``EFFECT`` (an
:class:`~msens.diagnose.effects.base.Effect`); :func:`registry` discovers it.
"""

from __future__ import annotations

import importlib
import pkgutil

from msens.diagnose.effects.base import (
    Context,
    Effect,
    FirstOrderLowpass,
    ModelState,
    Parameter,
    PhysicsMss,
)
from msens.errors import InputError

#: The fixed public names, in the order reports list them.
NAMES = ("wall_dissipation", "wall_stiffness", "striker_velocity", "magnetic_precompression",
         "contact_damping_law", "daq_lowpass", "sensor_position", "magnet_remanence",
         "coil_position", "cable_capacitance", "static_precompression", "sensor_mass",
         "tube_friction")


#: The effects that only a physics MsS (its field model and read-out) has.
PHYSICS_MSS_NAMES = ("magnet_remanence", "coil_position", "cable_capacitance")


def registry() -> dict[str, Effect]:
    """Every effect module of this package, by name (the fixed names first, in order)."""
    found = {}
    for info in pkgutil.iter_modules(__path__):
        if info.name == "base":
            continue
        module = importlib.import_module(f"{__name__}.{info.name}")
        effect = getattr(module, "EFFECT", None)
        if isinstance(effect, Effect):
            found[effect.name] = effect
    order = [n for n in NAMES if n in found] + sorted(set(found) - set(NAMES))
    return {n: found[n] for n in order}


def get(name: str) -> Effect:
    """The effect called ``name`` (InputError listing the known names otherwise)."""
    effects = registry()
    if name not in effects:
        raise InputError(f"unknown effect {name!r}; known: {', '.join(effects)}")
    return effects[name]


__all__ = ["NAMES", "PHYSICS_MSS_NAMES", "Context", "Effect", "FirstOrderLowpass",
           "ModelState", "Parameter", "PhysicsMss", "get", "registry"]
