"""Uncertain inputs as data: what a study does not know, with a distribution and its reason.

An uncertainty file (schema ``msens.uncertainty/1``) lists ``[[input]]`` tables, each naming
one input of the study by a dotted key (``striker.drop_height_m``,
``sensor[1].coil.axial_offset_m``, ``sensor.magnet.remanence_factor``), its distribution
(``uniform``, ``loguniform``, ``normal``, ``triangular``) in SI units, and why it is what it
is (``reason``: a tolerance, a datasheet spread, a literature range; ``source``: where the
numbers come from). :func:`load_inputs` reads and checks it once against a study:

- the name is one msens can vary (:data:`KINDS`, listed in the message otherwise);
- every value the distribution can give lies inside the input's physical range (a modulus
  is positive, a coil offset stays inside the field model's tabulated span): for an
  unbounded distribution (``normal``), the values between its :data:`TAIL` and 1 - TAIL
  quantiles, which is also where its samples are drawn;
- the study has the thing the input varies (a coil for ``sensor[i].coil.*``).

Each input is also told how it reaches the model (:attr:`UncertainInput.route`): through the
chain and read-out (sampled directly), through the field model's variants (sampled
directly through tables the field model already has), through a surrogate of the field
model built on a few solves (the steel's reversibility:
:class:`msens.magnetics.reversibility.ReversibilityFamily`), or held at its nominal value
with the reason why (a field input that needs solves this version does not make). Nothing
here solves or simulates: a bad file fails in milliseconds.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import stats

from msens.chain.model import DampingLaw
from msens.config.schema import MssModel
from msens.config.study import Study
from msens.errors import InputError, shorten
from msens.io.tomlreader import Table, read_document

SCHEMA = "msens.uncertainty/1"
#: Probability left out in each tail of an unbounded distribution: its checked range and
#: the range of its samples are its TAIL and 1 - TAIL quantiles (a normal: +-4.75 std).
TAIL = 1e-6
#: Distributions and their keys (SI values).
DISTRIBUTIONS = {"uniform": ("lower", "upper"), "loguniform": ("lower", "upper"),
                 "normal": ("mean", "std"), "triangular": ("lower", "mode", "upper")}

#: How an input reaches the model.
CHAIN, FIELD_TABLE, HELD = "chain and read-out", "field-model tables", "held at nominal"
#: Through a spline surrogate over a few field solves (the steel's reversibility).
FIELD_SURROGATE = "field-model surrogate"


@dataclass(frozen=True)
class Kind:
    """One kind of input msens can vary.

    Attributes
    ----------
    pattern : str
        Its name, ``[i]`` standing for a 1-based sensor index.
    unit : str
        SI unit ("1" for a factor).
    description : str
        What it is, for reports.
    field : bool
        Whether it changes the field model (the transducers) rather than the chain, striker
        or read-out circuit.
    """

    pattern: str
    unit: str
    description: str
    field: bool = False

    @property
    def regex(self) -> re.Pattern:
        """The names this kind matches."""
        return re.compile(re.escape(self.pattern).replace(r"\[i\]", r"\[([1-9][0-9]*)\]"))


#: Every input kind msens can vary, by pattern.
KINDS = {k.pattern: k for k in (
    Kind("chain.youngs_modulus_pa", "Pa", "Young's modulus of the beads"),
    Kind("chain.bead_diameter_m", "m", "bead diameter (chain contacts; the field model "
         "keeps its nominal bead)"),
    Kind("chain.bead_mass_kg", "kg", "bead mass"),
    Kind("chain.gamma_contact_kg_per_s", "kg/s", "contact dissipation gamma_c (paper Eq. 8)"),
    Kind("chain.gamma_wall_kg_per_s", "kg/s", "wall-contact dissipation gamma_w"),
    Kind("chain.wall.youngs_modulus_pa", "Pa", "Young's modulus of the wall"),
    Kind("striker.drop_height_m", "m", "striker drop height"),
    Kind("electronics.cable_capacitance_F", "F", "cable capacitance across each coil"),
    Kind("sensor[i].coil.turns", "1", "turns of the coil (count error in the same winding "
         "window)", field=True),
    Kind("sensor[i].coil.axial_offset_m", "m", "axial offset of the coil from its particle",
         field=True),
    Kind("sensor.magnet.remanence_factor", "1", "remanence of every bias magnet over its "
         "nominal value", field=True),
    Kind("sensor.magnet.length_factor", "1", "length of the equivalent bias magnet over its "
         "nominal value", field=True),
    Kind("sensor.magnet.radius_factor", "1", "radii of the equivalent bias magnet over their "
         "nominal values", field=True),
    Kind("field.reversibility", "1", "reversible fraction of the steel's differential "
         "susceptibility (small-signal permeability: 1 differential, ~0.1 reversible)",
         field=True),
    Kind("field.steel_conductivity_S_per_m", "S/m", "electrical conductivity of the bead "
         "steel (eddy currents)", field=True),
)}


@dataclass(frozen=True)
class Distribution:
    """A probability distribution of one input, SI.

    Attributes
    ----------
    kind : {"uniform", "loguniform", "normal", "triangular"}
    parameters : tuple of float
        In the order of :data:`DISTRIBUTIONS` (e.g. lower, upper).
    """

    kind: str
    parameters: tuple[float, ...]

    def frozen(self):
        """The scipy.stats frozen distribution."""
        p = self.parameters
        if self.kind == "uniform":
            return stats.uniform(loc=p[0], scale=p[1] - p[0])
        if self.kind == "loguniform":
            return stats.loguniform(p[0], p[1])
        if self.kind == "normal":
            return stats.norm(loc=p[0], scale=p[1])
        return stats.triang(c=(p[1] - p[0]) / (p[2] - p[0]), loc=p[0], scale=p[2] - p[0])

    @property
    def support(self) -> tuple[float, float]:
        """Smallest and largest value a sample can take, SI."""
        if self.kind in ("uniform", "loguniform", "triangular"):
            return self.parameters[0], self.parameters[-1]
        lo, hi = self.frozen().ppf([TAIL, 1.0 - TAIL])
        return float(lo), float(hi)

    @property
    def median(self) -> float:
        """The distribution's median, SI."""
        return float(self.frozen().ppf(0.5))

    def values(self, u: np.ndarray) -> np.ndarray:
        """Inverse-CDF transform of unit samples ``u`` (clipped to [TAIL, 1 - TAIL])."""
        return self.frozen().ppf(np.clip(u, TAIL, 1.0 - TAIL))

    def describe(self) -> str:
        """e.g. ``uniform(0.0067, 0.0077)``."""
        return f"{self.kind}({', '.join(f'{v:.6g}' for v in self.parameters)})"


@dataclass(frozen=True)
class UncertainInput:
    """One uncertain input of a study.

    Attributes
    ----------
    name : str
        Dotted key (see :data:`KINDS`).
    kind : Kind
    distribution : Distribution
    nominal : float
        The study's value, SI (1 for a factor).
    physical : tuple of float
        Physical range (lower, upper), SI.
    physical_reason : str
        Why the range is what it is.
    reason : str
        Why the distribution is what it is (tolerance, spread, literature range).
    source : str
        Where its numbers come from.
    route : str
        :data:`CHAIN`, :data:`FIELD_TABLE`, :data:`FIELD_SURROGATE` or :data:`HELD`.
    held_reason : str
        With :data:`HELD`, why the input is held at its nominal value ("" otherwise).
    sensor : int or None
        0-based index of the sensor a ``sensor[i].*`` input belongs to.
    """

    name: str
    kind: Kind
    distribution: Distribution
    nominal: float
    physical: tuple[float, float]
    physical_reason: str
    reason: str
    source: str
    route: str
    held_reason: str = ""
    sensor: int | None = None

    @property
    def propagated(self) -> bool:
        """Whether the input is sampled (not held at its nominal value)."""
        return self.route != HELD

    def to_json(self) -> dict:
        """The input for result files."""
        lo, hi = self.distribution.support
        return {"name": self.name, "unit": self.kind.unit, "description": self.kind.description,
                "distribution": self.distribution.kind,
                "parameters": dict(zip(DISTRIBUTIONS[self.distribution.kind],
                                       self.distribution.parameters, strict=True)),
                "support": [lo, hi], "nominal": self.nominal,
                "physical_range": list(self.physical), "physical_reason": self.physical_reason,
                "reason": self.reason, "source": self.source, "route": self.route,
                **({"held_reason": self.held_reason} if self.held_reason else {})}


@dataclass(frozen=True)
class InputSet:
    """The uncertain inputs of one study, as read from an uncertainty file.

    Attributes
    ----------
    inputs : tuple of UncertainInput
    source : str
        The file they were read from.
    """

    inputs: tuple[UncertainInput, ...]
    source: str

    @property
    def propagated(self) -> tuple[UncertainInput, ...]:
        """The sampled inputs, in file order."""
        return tuple(i for i in self.inputs if i.propagated)

    @property
    def held(self) -> tuple[UncertainInput, ...]:
        """The inputs held at their nominal values."""
        return tuple(i for i in self.inputs if not i.propagated)

    def values(self, u: np.ndarray) -> np.ndarray:
        """Input values (rows, propagated inputs), SI, of unit samples of the same shape."""
        u = np.atleast_2d(u)
        return np.column_stack([p.distribution.values(u[:, j])
                                for j, p in enumerate(self.propagated)])


def default_inputs_path(study: Study) -> Path:
    """The built-in uncertainty file of a built-in study (``uncertainty-<name>.toml``)."""
    from importlib import resources

    return Path(str(resources.files("msens") / "data" / f"uncertainty-{study.name}.toml"))


def load_inputs(path: str | Path | None, study: Study) -> InputSet:
    """Read and check an uncertainty file against ``study`` (no solve, no simulation).

    Parameters
    ----------
    path : str or Path or None
        ``msens.uncertainty/1`` TOML file; None: the built-in file of a built-in study.
    study : Study

    Returns
    -------
    InputSet

    Raises
    ------
    InputError
        One message naming the file, the input and what is allowed: unknown or repeated
        names, distributions with bad parameters or outside the physical range, an input
        the study has nothing to vary for.
    """
    if path is None:
        path = default_inputs_path(study)
        if not path.is_file():
            raise InputError(f"study {study.name!r} has no built-in uncertainty file: give "
                             "one with --inputs FILE (schema msens.uncertainty/1; see "
                             f"{default_inputs_path_example()})")
    from msens.io._files import read_text

    # a regular UTF-8 file of bounded size (/dev/zero was read until memory ran out)
    text = read_text(path, what="uncertainty file (--inputs)")
    return parse_inputs(text, study, source=str(path))


def default_inputs_path_example() -> Path:
    """The built-in uncertainty file of the main study (an example of the format)."""
    from importlib import resources

    return Path(str(resources.files("msens") / "data" / "uncertainty-paper-mss.toml"))


def parse_inputs(text: str, study: Study, *, source: str = "<memory>") -> InputSet:
    """Check the TOML ``text`` of an uncertainty file (see :func:`load_inputs`)."""
    root = read_document(text, source=source, schema=SCHEMA)
    written_for = root.string("study")
    if written_for is not None and written_for != study.name:
        raise root.error("study", f"names the study {written_for!r}, but the inputs are "
                         f"applied to study {study.name!r}: use the uncertainty file written "
                         "for it, or change 'study'")
    tables = root.tables("input")
    root.finish()
    if not tables:
        raise InputError(f"{source}: no [[input]] tables: declare at least one uncertain "
                         "input (name, distribution, its parameters, reason)")
    out, seen = [], set()
    for t in tables:
        item = _input(t, study, source)
        if item.name in seen:
            raise t.error("name", f"repeats the input {item.name!r}: declare each input once")
        seen.add(item.name)
        out.append(item)
    inputs = InputSet(tuple(out), source)
    if not inputs.propagated:
        raise InputError(f"{source}: every input is held at its nominal value "
                         f"({'; '.join(f'{i.name}: {i.held_reason}' for i in out)}): nothing "
                         "to propagate")
    return inputs


def _kind(name: str, t: Table) -> tuple[Kind, int | None]:
    for kind in KINDS.values():
        m = kind.regex.fullmatch(name)
        if m:
            return kind, (int(m.group(1)) - 1 if m.groups() else None)
    allowed = ", ".join(KINDS)
    raise t.error("name", f"is not an input msens can vary: {shorten(name)}; allowed: "
                  f"{allowed} ([i]: a sensor's 1-based index)")


def _distribution(t: Table) -> Distribution:
    kind = t.string("distribution", required=True, choices=tuple(DISTRIBUTIONS))
    keys = DISTRIBUTIONS[kind]
    values = tuple(t.number(k, required=True) for k in keys)
    where = f"'{t.key('distribution')}' = {kind!r}"
    if kind in ("uniform", "loguniform") and not values[0] < values[1]:
        raise t.error("upper", f"must be above 'lower' ({values[0]:g}) for {where}, got "
                      f"{values[1]:g}")
    if kind == "loguniform" and not values[0] > 0:
        raise t.error("lower", f"must be > 0 for {where}, got {values[0]:g}")
    if kind == "normal" and not values[1] > 0:
        raise t.error("std", f"must be > 0 for {where}, got {values[1]:g}")
    if kind == "triangular" and not (values[0] <= values[1] <= values[2]
                                     and values[0] < values[2]):
        raise t.error("mode", f"must satisfy lower <= mode <= upper (lower < upper) for "
                      f"{where}, got {values}")
    return Distribution(kind, values)


def _input(t: Table, study: Study, source: str) -> UncertainInput:
    name = t.string("name", required=True)
    kind, sensor = _kind(name, t)
    dist = _distribution(t)
    reason = t.string("reason", required=True)
    src = t.string("source", "")
    t.finish()
    if not reason.strip():
        raise t.error("reason", "is empty: say why the distribution is what it is (a "
                      "tolerance, a datasheet spread, a literature range)")
    nominal, (lo, hi), why = _nominal_and_range(kind, sensor, study, t)
    a, b = dist.support
    slack = 1e-12 * max(abs(lo), abs(hi), 1e-300)
    if not (lo - slack <= a and b <= hi + slack) or not (math.isfinite(a) and math.isfinite(b)):
        span = "its samples span" if dist.kind != "normal" else \
            f"its {TAIL:g} to {1 - TAIL:g} quantiles span"
        raise t.error("distribution", f"{dist.describe()} of input {name!r} leaves the "
                      f"input's physical range: {span} {a:.6g}..{b:.6g} {kind.unit}, allowed "
                      f"{lo:.6g}..{hi:.6g} {kind.unit} ({why})")
    route, held = _route(kind, study)
    return UncertainInput(name=name, kind=kind, distribution=dist, nominal=nominal,
                          physical=(lo, hi), physical_reason=why, reason=reason.strip(),
                          source=src.strip(), route=route, held_reason=held, sensor=sensor)


def _nominal_and_range(kind: Kind, sensor: int | None, study: Study,
                       t: Table) -> tuple[float, tuple[float, float], str]:
    # the study's value of the input, its physical range (SI) and the range's reason
    from msens.magnetics import reversibility
    from msens.magnetics.mechanisms import OFFSET_SPAN
    from msens.magnetics.variants import NODES
    from msens.params.materials import SIGMA_1018

    c, p = study.chain, kind.pattern
    stiff = (1e9, 1.2e12, "1 GPa (a hard polymer) to 1200 GPa (diamond, the stiffest solid)")
    if p in ("chain.gamma_contact_kg_per_s", "chain.gamma_wall_kg_per_s") and \
            c.damping is DampingLaw.HERTZ_KUWABARA_KONO:
        raise t.error("name", f"{p} is a linear dashpot coefficient, but the study's damping "
                      "is 'hertz-kuwabara-kono': its coefficients cannot be varied here yet")
    if p == "chain.youngs_modulus_pa":
        return c.youngs_modulus_pa, stiff[:2], stiff[2]
    if p == "chain.wall.youngs_modulus_pa":
        return c.wall.youngs_modulus_pa, stiff[:2], stiff[2]
    if p == "chain.bead_diameter_m":
        d = c.bead_diameter_m
        return d, (0.9 * d, 1.1 * d), ("within 10 % of the study's bead: the field model and "
                                       "the tube are built for it, a larger change is another "
                                       "chain, not a tolerance")
    if p == "chain.bead_mass_kg":
        m = c.bead_mass_kg
        return m, (0.8 * m, 1.2 * m), ("within 20 % of the study's bead mass (steel densities "
                                       "span 7.7-8.1 g/cm3; a larger change is another bead)")
    if p in ("chain.gamma_contact_kg_per_s", "chain.gamma_wall_kg_per_s"):
        value = c.gamma_contact if p == "chain.gamma_contact_kg_per_s" else c.gamma_wall
        return value, (0.0, 150.0), ("0 to the critical damping of a contact of these beads "
                                     "(2 sqrt(k m) ~ 150 kg/s at a 5 N pulse)")
    if p == "striker.drop_height_m":
        h = study.striker.drop_height_m
        if h is None:
            raise t.error("name", "striker.drop_height_m: the study gives the striker's speed "
                          "('striker.velocity_m_per_s'), not a drop height")
        return h, (1e-5, 0.1), ("0.01 mm to 10 cm: a drop inside a guide tube (the chain "
                                "model has no plasticity for harder impacts)")
    if p == "electronics.cable_capacitance_F":
        return study.electronics.cable_capacitance_f, (0.0, 10e-9), \
            "up to 100 m of RG-58 (100 pF/m)"
    if p.startswith("sensor[i]"):
        sensors = study.setups[0].sensors
        if sensor >= len(sensors) or sensors[sensor].model is not MssModel.PHYSICS:
            raise t.error("name", f"sensor[{sensor + 1}] is not a physics MsS of the study "
                          f"(its physics MsS are sensor"
                          f"{[i + 1 for i, s in enumerate(sensors) if s.model is MssModel.PHYSICS]}"
                          ")")
        coil = sensors[sensor].coil
        if p.endswith("turns"):
            n = float(coil.turns) if coil else 1100.0
            return n, (0.8 * n, 1.2 * n), ("within 20 % of the study's turns: a miscount in "
                                           "the same winding window (more is another coil)")
        return 0.0, (-OFFSET_SPAN, OFFSET_SPAN), \
            f"the field model tabulates coil offsets over +-{OFFSET_SPAN * 1e3:g} mm"
    if not any(s.model is MssModel.PHYSICS for s in study.setups[0].sensors) and \
            p != "field.steel_conductivity_S_per_m":
        raise t.error("name", f"{p}: the study has no physics MsS sensor, so no field model "
                      "to vary")
    if p == "sensor.magnet.remanence_factor":
        return 1.0, (NODES[0], NODES[-1]), ("the remanence family's span of field models "
                                            "(msens.magnetics.variants.NODES)")
    if p in ("sensor.magnet.length_factor", "sensor.magnet.radius_factor"):
        return 1.0, (0.5, 2.0), "half to twice the equivalent magnet's nominal size"
    if p == "field.reversibility":
        value = study.field.steel_reversibility
        lo, hi = reversibility.NODES[0], reversibility.NODES[-1]  # the surrogate's span
        return value, (lo, hi), (f"the span {lo:g}..{hi:g} of the surrogate's field models "
                                 "(msens.magnetics.reversibility.NODES) within (0, 1], "
                                 "Jiles-Atherton's c")
    value = study.field.steel_conductivity_s_per_m or SIGMA_1018
    return value, (1e5, 6.3e7), ("1e5 S/m to silver's 6.3e7 S/m (carbon steels: 5-7e6 S/m)")


def _route(kind: Kind, study: Study) -> tuple[str, str]:
    # how the input reaches the model, and why it is held if it is
    p, eddy = kind.pattern, study.field.eddy_currents
    if not kind.field:
        return CHAIN, ""
    if p == "field.steel_conductivity_S_per_m" and not eddy:
        return HELD, ("does not enter this study's physics: [field] eddy_currents = false (the "
                      "steel's conductivity only sets the eddy currents)")
    if p == "field.steel_conductivity_S_per_m":
        return HELD, ("sets the eddy currents in the steel: it needs eddy-current models over "
                      "the conductivity, not solved in this version; the band is conditional "
                      "on the nominal value")
    if p in ("sensor[i].coil.turns", "sensor[i].coil.axial_offset_m",
             "sensor.magnet.remanence_factor"):  # with eddy currents: msens.uq.model.response_at
        return FIELD_TABLE, ""
    if p == "field.reversibility":  # with eddy currents the responses' surrogate too
        return FIELD_SURROGATE, ""
    return HELD, ("changes the field model's bias solve: it needs a design of field solves "
                  "and a surrogate with its error measured on held-out solves, not made in "
                  "this version; the band is conditional on the nominal value")


__all__ = ["CHAIN", "DISTRIBUTIONS", "FIELD_SURROGATE", "FIELD_TABLE", "HELD", "KINDS",
           "SCHEMA", "TAIL",
           "Distribution", "InputSet", "Kind", "UncertainInput", "default_inputs_path",
           "load_inputs", "parse_inputs"]
