"""One canonical form and content hash for every cache key (msens.io.hashing)."""

from __future__ import annotations

import dataclasses
import enum
import hashlib
from pathlib import Path

import numpy as np

from msens.io.hashing import canonical, canonical_json, content_hash


class _Law(enum.Enum):
    LINEAR = "linear"


@dataclasses.dataclass(frozen=True)
class _Part:
    radius: float
    grade: str = dataclasses.field(default="n42", metadata={"mesh": False})


def test_the_text_is_sorted_compact_json_with_floats_by_repr():
    """The format every stored key depends on: a change here orphans the committed caches."""
    obj = {"b": 1, "a": [1.5, "x", None, True], "c": _Part(0.1)}
    text = ('{"a":["1.5","x",null,true],"b":1,'
            '"c":{"__type__":"_Part","grade":"n42","radius":"0.1"}}')
    assert canonical_json(obj) == text
    assert content_hash(obj) == hashlib.sha256(text.encode()).hexdigest()
    assert content_hash(obj, 16) == content_hash(obj)[:16]


def test_equal_content_gives_equal_keys_and_any_change_another():
    assert content_hash({"x": 1.0, "y": [2, 3]}) == content_hash({"y": (2, 3), "x": 1.0})
    assert content_hash(np.array([[1.5, 2.0]])) == content_hash([[1.5, 2.0]])
    assert content_hash(np.int64(3)) == content_hash(3)
    assert content_hash(_Law.LINEAR) == content_hash("linear")
    assert content_hash(Path("a/b")) == content_hash("a/b")
    assert content_hash(0.1) != content_hash(np.nextafter(0.1, 1.0).item())
    assert content_hash({"k": 1}) != content_hash({"k": 1.0})


def test_a_field_filter_leaves_fields_out():
    def geometry_only(f, value):
        return f.metadata.get("mesh", True)

    assert canonical(_Part(2e-3, "n52"), geometry_only) == {"__type__": "_Part",
                                                            "radius": "0.002"}
    assert content_hash(_Part(2e-3, "n52"), include=geometry_only) == \
        content_hash(_Part(2e-3), include=geometry_only)
    assert content_hash(_Part(2e-3, "n52")) != content_hash(_Part(2e-3))
