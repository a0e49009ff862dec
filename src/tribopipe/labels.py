"""What a run is, and its QC flags: decided once, before anything is printed or stored.

:class:`RunLabels` say what a run is (pair and nominal conditions, as the user or a
campaign's metadata gave them); :class:`Tolerances` how far its measured conditions may
stray from them. :func:`decide_run` turns the labels and what the reduction measured into
a :class:`RunVerdict`: the nominal force the run is grouped under (estimated from the
measured mean when none was given) and the run's one list of flags (the reduction's own
and the off-nominal ones of :func:`qc_flags`). Every output of a run (the ``reduce``
table and JSON, the summary, the trace plot, the map row, ``runs.csv``) shows
``RunVerdict.flags``; nothing decides a flag again downstream.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field, replace

from .config import InstrumentConfig
from .errors import CampaignError
from .materials import Vocabulary, shipped_vocabulary
from .numeric import is_finite
from .physics import sliding_speed_mm_s
from .reporting import RunReport
from .rounding import round_significant
from .validate import FORCE_N, MAX_REPEAT, TEMPERATURE_C, check_count, check_name, check_number

#: Flag added when the nominal force was not given and the measured mean was used.
FLAG_FORCE_ESTIMATED = "nominal_force_estimated"
#: Flags added when a run strays from its nominal conditions (:func:`qc_flags`).
FLAG_FORCE_OFF = "normal_force_off_nominal"
FLAG_TEMPERATURE_OFF = "temperature_off_nominal"
FLAG_SPEED_OFF = "sliding_speed_off_nominal"
#: Significant digits of a nominal sliding speed: the rotational-speed set point [rpm] is
#: rounded to them (0.00503 rpm measured is the 0.005 rpm set point), and so is the nominal
#: sliding speed [mm/s] it gives, as the map groups and prints it (0.0070 mm/s)
SPEED_SIGNIFICANT = 2
#: Flag of a run reduced from a synthetic export (written by a generator, not measured):
#: a campaign with ``synthetic = true`` (the shipped demo) gives it to every run.
FLAG_SYNTHETIC = "synthetic"
#: Flags that say where a run came from, not how it went: no quality flag (a synthetic
#: campaign's every run carries one; it is said once, not per run or group).
PROVENANCE_FLAGS: frozenset[str] = frozenset({FLAG_SYNTHETIC})


#: How a map row, ``runs.csv`` and the campaign state keep a run's flags in one text cell.
FLAGS_SEPARATOR = ";"


def flags_text(flags: Iterable[str]) -> str:
    """``flags`` as the one text cell a map row keeps (``""`` for none)."""
    return FLAGS_SEPARATOR.join(flags)


def flag_list(flags: object) -> list[str]:
    """The flags in ``flags`` (a text cell as :func:`flags_text` writes it, or a sequence
    of flags), in their order, without empties; none for a missing value (``None``,
    NaN)."""
    if isinstance(flags, str):
        items: list[str] = flags.split(FLAGS_SEPARATOR)
    elif isinstance(flags, (list, tuple)):
        items = [str(f) for f in flags]
    else:
        items = []
    return [f for f in (i.strip() for i in items) if f]


def quality_flags(flags: object) -> list[str]:
    """The QC flags among ``flags`` (as :func:`flag_list` takes them), in their order,
    without :data:`PROVENANCE_FLAGS`; none for a missing value."""
    return [f for f in flag_list(flags) if f not in PROVENANCE_FLAGS]


@dataclass(frozen=True)
class RunLabels:
    """What a run is: contact pair and nominal conditions (not measured values).

    ``normal_force_N`` is the nominal total normal force on the three pins [N] and
    ``temperature_C`` the nominal chamber temperature [°C]; both define the condition
    group in the friction map. ``None`` means unknown.

    Every given label is checked where it is made (:mod:`tribopipe.validate`): names are
    one line of printable text, the force is in :data:`~tribopipe.validate.FORCE_N`, the
    temperature in :data:`~tribopipe.validate.TEMPERATURE_C`, the repeat a whole number;
    otherwise :class:`~tribopipe.errors.ValidationError` names the label.
    """

    pin: str | None = None
    disc: str | None = None
    normal_force_N: float | None = None
    temperature_C: float | None = None
    repeat: int | None = None
    #: the names as they came in, before the materials vocabulary resolved them
    #: (:mod:`tribopipe.materials`); ``None``: as ``pin``/``disc``, or not resolved
    pin_as_given: str | None = None
    disc_as_given: str | None = None
    #: the run's reporting items (:mod:`tribopipe.reporting`): humidity, roughness, ...
    report: RunReport = field(default_factory=RunReport)

    def __post_init__(self) -> None:
        for name in ("pin", "disc"):
            value = getattr(self, name)
            if value is not None:
                check_name(value, name)
        if self.normal_force_N is not None:
            check_number(self.normal_force_N, FORCE_N, "nominal normal force")
        if self.temperature_C is not None:
            check_number(self.temperature_C, TEMPERATURE_C, "nominal temperature")
        if self.repeat is not None:
            check_count(self.repeat, "repeat", high=MAX_REPEAT)

    def resolved(self, vocabulary: Vocabulary) -> RunLabels:
        """These labels with pin and disc resolved through ``vocabulary``
        (:meth:`tribopipe.materials.Vocabulary.resolve_all`: the canonical name, the given
        one kept in ``pin_as_given``/``disc_as_given``); a name that does not resolve
        refuses the labels, ONE :class:`~tribopipe.materials.MaterialError` naming each
        such name with its did-you-mean and the fix."""
        named = [(what, getattr(self, what)) for what in ("pin", "disc")
                 if getattr(self, what) is not None]
        found = vocabulary.resolve_all(named)
        out = self
        if self.pin is not None:
            out = replace(out, pin=found[("pin", self.pin)],
                          pin_as_given=self.pin_as_given or self.pin)
        if self.disc is not None:
            out = replace(out, disc=found[("disc", self.disc)],
                          disc_as_given=self.disc_as_given or self.disc)
        return out

    @property
    def complete(self) -> bool:
        """True when pin and disc are known (the minimum for a friction-map row)."""
        return bool(self.pin) and bool(self.disc)


@dataclass(frozen=True)
class Tolerances:
    """How far a run's measured conditions may stray from nominal before it is flagged.

    The normal force limit is ``max(force_N, force_rel · F_nominal)`` [N]; the temperature
    limit is ``temperature_C`` [K, as a difference in °C]; the sliding speed limit is
    ``speed_rel · v_nominal`` [mm/s]. Defaults: 10 % of the nominal force, 2 K, 10 % of the
    nominal speed (a campaign config may state its own).
    """

    force_N: float = 0.0
    force_rel: float = 0.10
    temperature_C: float = 2.0
    speed_rel: float = 0.10

    def force_limit_N(self, nominal_N: float) -> float:
        """Allowed |F_measured − F_nominal| [N] at a nominal total force [N]."""
        return max(self.force_N, self.force_rel * abs(nominal_N))


#: The default stated tolerance beyond which a measured mean normal force refuses its
#: label: 25 % of the nominal force. A 10 % deviation is a QC flag
#: (:data:`FLAG_FORCE_OFF`); a run measured at 5 N and labelled 9 N (44 %) is mislabelled.
LABEL_FORCE_REL = 0.25


class LabelMismatch(CampaignError):
    """A run's labels contradict its own export (measured force, Test name, sample): the
    run is refused unless the labels are kept explicitly (``--keep-labels``)."""


@dataclass(frozen=True)
class LabelCheck:
    """How a run's labels are checked against its export before it is stored:
    ``force_rel``, the stated tolerance (a fraction of the nominal force) beyond which the
    measured mean normal force refuses the label; ``vocabulary``, the materials a Test
    name or sample field is read for (``None``: the shipped one); ``keep_labels`` keeps
    the labels whatever the export says (the run is then only flagged)."""

    force_rel: float = LABEL_FORCE_REL
    keep_labels: bool = False
    vocabulary: Vocabulary | None = None

    def problems(self, labels: RunLabels, normal_force_measured_N: float | None,
                 texts: Iterable[tuple[str, str | None]]) -> list[str]:
        """What in the export contradicts ``labels`` (none with ``keep_labels``): the
        measured mean normal force [N] beyond ``force_rel`` of the nominal (both values),
        and each of ``texts`` (``(what, text)``: the Test name, the sample field) that
        names materials other than the labelled pin and disc
        (:meth:`tribopipe.materials.Vocabulary.mentioned`)."""
        if self.keep_labels:
            return []
        out = []
        nominal = labels.normal_force_N
        if nominal is not None and normal_force_measured_N is not None and \
                is_finite(normal_force_measured_N) and nominal > 0:
            off = abs(normal_force_measured_N - nominal) / nominal
            if off > self.force_rel:
                out.append(f"measured mean normal force {normal_force_measured_N:.3g} N is "
                           f"{off:.0%} off the label {nominal:g} N (stated tolerance "
                           f"{self.force_rel:.0%})")
        vocabulary = self.vocabulary or shipped_vocabulary()
        labelled = {labels.pin, labels.disc} - {None}
        # names compare only when both labels are the vocabulary's own
        if labels.complete and all(name in vocabulary for name in labelled):
            for what, text in texts:
                if not text:
                    continue
                named = vocabulary.mentioned(text)
                others = [choices for choices in named if not set(choices) & labelled]
                if others:
                    names = ", ".join(" or ".join(repr(c) for c in choices)
                                      for choices in others)
                    out.append(f"{what} {text!r} names {names}, the labels say pin "
                               f"{labels.pin!r} on disc {labels.disc!r}")
        return out

    def check(self, labels: RunLabels, normal_force_measured_N: float | None,
              texts: Iterable[tuple[str, str | None]]) -> None:
        """:meth:`problems` as one :class:`LabelMismatch` line, with the way out."""
        found = self.problems(labels, normal_force_measured_N, texts)
        if found:
            raise LabelMismatch("labels contradict the export: " + "; ".join(found),
                                hint="fix the labels, or keep them with --keep-labels "
                                     "(a campaign: keep_labels = true)")


def round_speed(value: float) -> float:
    """A speed (any unit) rounded to :data:`SPEED_SIGNIFICANT` significant digits: the
    one rounding rule of nominal speeds (0 and non-finite unchanged)."""
    return round_significant(value, SPEED_SIGNIFICANT)


def nominal_speed_mm_s(set_point_rpm: float | None, instrument: InstrumentConfig) -> float:
    """The nominal sliding speed [mm/s] of a run: its interval's rotational-speed set point
    [rpm] (else the instrument's ``nominal_speed_rpm``), rounded to
    :data:`SPEED_SIGNIFICANT` significant digits, times the friction radius, rounded
    again the same way (the one rounding rule of nominal speeds: the map groups by it).
    A linear instrument without a rotational set point slides at its
    ``nominal_speed_mm_s`` (rounded the same way)."""
    no_set_point = set_point_rpm is None or not is_finite(set_point_rpm) or set_point_rpm <= 0
    if no_set_point and instrument.nominal_speed_mm_s is not None:
        return round_speed(float(instrument.nominal_speed_mm_s))
    rpm = set_point_rpm if set_point_rpm is not None and is_finite(set_point_rpm) and \
        set_point_rpm > 0 else instrument.nominal_speed_rpm
    return round_speed(sliding_speed_mm_s(round_speed(rpm), instrument.friction_radius_mm))


def qc_flags(labels: RunLabels, normal_force_measured_N: float | None,
             temperature_measured_C: float | None, tolerances: Tolerances) -> list[str]:
    """The off-nominal QC flags of a run: ``normal_force_off_nominal`` when the measured
    mean normal force [N] strays more than the tolerance from nominal,
    ``temperature_off_nominal`` likewise for the temperature [°C]. Unknown nominal or
    measured values (``None`` or NaN) raise no flag."""
    flags: list[str] = []
    if labels.normal_force_N is not None and normal_force_measured_N is not None and \
            is_finite(normal_force_measured_N):
        if abs(normal_force_measured_N - labels.normal_force_N) > \
                tolerances.force_limit_N(labels.normal_force_N):
            flags.append(FLAG_FORCE_OFF)
    if labels.temperature_C is not None and temperature_measured_C is not None and \
            is_finite(temperature_measured_C):
        if abs(temperature_measured_C - labels.temperature_C) > tolerances.temperature_C:
            flags.append(FLAG_TEMPERATURE_OFF)
    return flags


def speed_flags(nominal_mm_s: float | None, measured_mm_s: float | None,
                tolerances: Tolerances) -> list[str]:
    """``sliding_speed_off_nominal`` when the measured sliding speed [mm/s] strays more
    than ``tolerances.speed_rel`` of the nominal from it; unknown values raise nothing."""
    if nominal_mm_s is None or measured_mm_s is None or not is_finite(measured_mm_s) or \
            not is_finite(nominal_mm_s) or nominal_mm_s <= 0:
        return []
    if abs(measured_mm_s - nominal_mm_s) > tolerances.speed_rel * nominal_mm_s:
        return [FLAG_SPEED_OFF]
    return []


def canonical_flags(flags: Iterable[str]) -> tuple[str, ...]:
    """Flags as every output shows them: sorted and unique, so the same run always shows
    the same list (and the map the same ``;``-joined string)."""
    return tuple(sorted({f for f in flags if f}))


@dataclass(frozen=True)
class RunVerdict:
    """A run's labels with what they decide: ``normal_force_N``, the nominal total force
    [N] the run is grouped under (the label, or the measured mean rounded to 0.1 N when
    none was given; ``None`` when neither is known), ``flags``, the run's one list of
    QC flags (:func:`canonical_flags`), and ``nominal_speed_mm_s``, the nominal sliding
    speed [mm/s] the run is grouped under (:func:`nominal_speed_mm_s`)."""

    labels: RunLabels
    normal_force_N: float | None
    flags: tuple[str, ...]
    nominal_speed_mm_s: float | None = None


def decide_run(labels: RunLabels, reduction_flags: Iterable[str],
               normal_force_measured_N: float | None, temperature_measured_C: float | None,
               tolerances: Tolerances | None = None,
               extra_flags: Iterable[str] = (), *,
               speed_set_point_rpm: float | None = None,
               sliding_speed_measured_mm_s: float | None = None,
               instrument: InstrumentConfig | None = None) -> RunVerdict:
    """Decide a reduced run's nominal force and flags, once, from its labels, the flags of
    its reduction and its measured mean normal force [N] and temperature [°C]
    (``tolerances`` default: :class:`Tolerances`, 10 %, 2 K).

    The flags are the reduction's, the off-nominal ones (:func:`qc_flags`),
    ``nominal_force_estimated`` when no nominal force was given and the measured mean
    (rounded to 0.1 N) stands in for it, and ``extra_flags`` of the run's source (e.g.
    :data:`FLAG_SYNTHETIC` for a synthetic campaign). The nominal sliding speed [mm/s]
    is :func:`nominal_speed_mm_s` of the interval's set point ``speed_set_point_rpm``
    (else the ``instrument``'s nominal speed; default :class:`InstrumentConfig`), and
    ``sliding_speed_off_nominal`` flags a measured speed [mm/s] off it (:func:`speed_flags`).
    """
    tolerances = tolerances or Tolerances()
    speed = nominal_speed_mm_s(speed_set_point_rpm, instrument or InstrumentConfig())
    flags = [*reduction_flags, *extra_flags]
    flags += qc_flags(labels, normal_force_measured_N, temperature_measured_C, tolerances)
    flags += speed_flags(speed, sliding_speed_measured_mm_s, tolerances)
    force: float | None
    if labels.normal_force_N is not None:
        force = float(labels.normal_force_N)
    elif normal_force_measured_N is not None and is_finite(normal_force_measured_N):
        force = round(float(normal_force_measured_N), 1)
        flags.append(FLAG_FORCE_ESTIMATED)
    else:
        force = None
    return RunVerdict(labels=labels, normal_force_N=force, flags=canonical_flags(flags),
                      nominal_speed_mm_s=speed)


class Undescribed(CampaignError):
    """No metadata source describes a run's test: it cannot be labelled (a campaign's
    ledger names these apart from other failures)."""
