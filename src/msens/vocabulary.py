"""One name per concept in every figure: sensors, contacts, setups and the time axis.

Every figure (``msens run``, ``field``, ``compare``, ``diagnose``, ``design``) takes its
labels from here, so that the same thing is called the same way in all of them:

========================  =====================================================
concept                   name in figures
========================  =====================================================
time axis                 "time since striker impact (µs)": t = 0 when the striker
                          touches the first bead, in every figure (a measured record
                          is put on this axis by its fitted trigger delay)
bead sensor               "bead sensor at particle 13"
rod sensor                "rod sensor at particle 13"
MsS (either model)        "coil at particle 13": the MsS is the coil wound around
                          particle 13 (four-contact mean or physics read-out alike)
contact                   "contact 11 (particles 11, 12)"; contact c joins
                          particles c and c+1, counted from the striker
setup                     "setup bead"
========================  =====================================================

Data files keep their own keys (``"mss@13"`` in JSON, ``c11`` nowhere in figures):
:func:`channel_name` turns such a key into the figure name.
"""

from __future__ import annotations

import re

#: What t = 0 is, in every figure.
TIME_ORIGIN = "time since striker impact"
#: The time axis of every figure of a record.
TIME_LABEL = f"{TIME_ORIGIN} (µs)"
#: The contact axis of profiles along the chain.
CONTACT_AXIS = "contact c (between particles c and c+1)"

_KINDS = {"bead": "bead sensor", "rod": "rod sensor", "mss": "coil"}


def sensor_name(kind, particle: int) -> str:
    """Figure name of a sensor: "bead sensor at particle 13", "coil at particle 13".

    Parameters
    ----------
    kind : str or SensorKind
        "bead", "rod" or "mss" (an enum member's ``value`` is read).
    particle : int
        1-based particle the sensor sits on (its coil's centre for an MsS).

    Returns
    -------
    str
    """
    k = getattr(kind, "value", kind)
    return f"{_KINDS.get(k, f'{k} sensor')} at particle {int(particle)}"


def coil_name(particle: int) -> str:
    """Figure name of an MsS coil (its sensor name): "coil at particle 13"."""
    return sensor_name("mss", particle)


_TAG = re.compile(r"([a-z]+)@(\d+)")


def channel_name(tag: str) -> str:
    """Figure name of a data key "kind@particle" ("mss@13" -> "coil at particle 13"), also
    inside a longer text ("bead@13 (top)" -> "bead sensor at particle 13 (top)"); any other
    text is returned unchanged."""
    return _TAG.sub(lambda m: sensor_name(m[1], int(m[2])), tag)


def contact_name(c: int, *, particles: bool = True) -> str:
    """Figure name of contact ``c`` (1-based, joins particles c and c+1):
    "contact 11 (particles 11, 12)", or "contact 11" without ``particles``."""
    c = int(c)
    return f"contact {c} (particles {c}, {c + 1})" if particles else f"contact {c}"


def setup_name(name: str) -> str:
    """Figure name of a study setup: "setup bead"."""
    return f"setup {name}"


__all__ = ["CONTACT_AXIS", "TIME_LABEL", "TIME_ORIGIN", "channel_name", "coil_name",
           "contact_name", "sensor_name", "setup_name"]
