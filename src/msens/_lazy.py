"""Public names of a package loaded from their modules on first use (:pep:`562`).

A package lists where each of its public names lives; ``import msens.<package>`` then costs
nothing beyond the package itself, and importing one module of it (``msens.mechanics.hertz``)
does not load its heavy siblings (``msens.mechanics.elasticity`` and scikit-fem)::

    _HOMES = {"hertz": ("hertz_energy", "hertz_sphere_flat"), "longwave": ("sound_speed",)}
    __all__ = names(_HOMES)


    def __getattr__(name):
        return attribute(__name__, _HOMES, name)
"""

from __future__ import annotations

import sys
from collections.abc import Mapping
from importlib import import_module


def names(homes: Mapping[str, tuple[str, ...]]) -> list[str]:
    """The public names of a package, sorted, from its table ``{module: names}``.

    Raises
    ------
    InternalError
        If a name is listed under two modules.
    """
    from msens.errors import internal

    found = [n for listed in homes.values() for n in listed]
    internal(len(found) == len(set(found)),
             f"a public name is listed twice: {sorted(n for n in found if found.count(n) > 1)}")
    return sorted(found)


def attribute(package: str, homes: Mapping[str, tuple[str, ...]], name: str):
    """The public ``name`` of ``package`` (a module-level ``__getattr__``), imported from the
    module ``homes`` lists it under and kept in the package's namespace.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    homes : mapping of str to tuple of str
        ``{module name relative to the package: public names it defines}``.
    name : str
        The attribute asked for.

    Raises
    ------
    AttributeError
        If ``name`` is not a public name of the package.
    """
    for module, listed in homes.items():
        if name in listed:
            value = getattr(import_module(f"{package}.{module}"), name)
            setattr(sys.modules[package], name, value)
            return value
    raise AttributeError(f"module {package!r} has no attribute {name!r}")
