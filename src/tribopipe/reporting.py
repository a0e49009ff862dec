"""The reporting items that make two labs' runs comparable, and the values a run carries.

ASTM G115 (measuring and reporting friction coefficients), ASTM D1894 and ISO 8295 ask a
friction test to report, beside the coefficients and the nominal conditions the map
already keeps, the environment (relative humidity), the specimens' surface (roughness,
finish), how they were prepared (batch, cure, conditioning) and the apparatus (instrument,
serial number, software version), who measured and when. :data:`ITEMS` is the one list of
them: each becomes a map column (:mod:`tribopipe.frictionmap.schema`, schema version 6),
a manifest column and a key of a campaign's ``[metadata]`` table, and goes through
``runs.csv`` and a published package. A manifest column tribopipe does not know is kept
as extra metadata (``extra_metadata``, a JSON object of text values), never dropped.

:func:`parse_item` checks one value from outside (a manifest cell, a campaign key, an
export header) and returns it typed; :class:`RunReport` holds a run's values.
"""

from __future__ import annotations

import json
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from .errors import ValidationError
from .validate import Range, check_number, text_problem


@dataclass(frozen=True)
class Item:
    """One reporting item: its map column ``name`` (the unit in the name), ``kind``
    (``"float"`` or ``"str"``), ``unit``, ``meaning``, physical ``bounds`` of a number
    and the ASTM G115 report item it covers (``g115``)."""

    name: str
    kind: str
    unit: str
    meaning: str
    g115: str
    bounds: Range | None = None


#: relative humidity [%]
HUMIDITY_PCT = Range(0.0, 100.0, "%")
#: a roughness Ra [µm]
RA_UM = Range(0.0, 1e4, "µm")
#: a conditioning time [h]
CONDITIONING_H = Range(0.0, 1e6, "h")

#: The reporting items, in the order the map keeps them.
ITEMS: tuple[Item, ...] = (
    Item("humidity_pct", "float", "%", "relative humidity during the run",
         "test environment: relative humidity", HUMIDITY_PCT),
    Item("disc_Ra_um", "float", "µm", "arithmetic mean roughness Ra of the disc",
         "specimen surface: roughness", RA_UM),
    Item("surface_finish", "str", "", "the disc's surface finish (as the lab states it)",
         "specimen surface: finish and preparation"),
    Item("specimen_batch", "str", "", "batch of the pin (and disc) specimens",
         "specimen: material identification (lot)"),
    Item("specimen_cure", "str", "", "how the specimens were cured (schedule, as stated)",
         "specimen preparation"),
    Item("conditioning_h", "float", "h", "conditioning time of the specimens before the "
         "run", "specimen conditioning", CONDITIONING_H),
    Item("instrument", "str", "", "instrument (make and model)", "apparatus"),
    Item("instrument_serial", "str", "", "serial number of the instrument", "apparatus"),
    Item("software_version", "str", "", "acquisition software and its version",
         "apparatus: data acquisition"),
    Item("operator", "str", "", "who ran the test", "test record: operator"),
    Item("measured_on", "str", "", "date (and time) of the run, as given (ISO 8601 "
         "preferred)", "test record: date"),
)
#: the map column of the columns a manifest holds that tribopipe does not know
EXTRA_COLUMN = "extra_metadata"
#: the item names
NAMES: tuple[str, ...] = tuple(i.name for i in ITEMS)
BY_NAME: dict[str, Item] = {i.name: i for i in ITEMS}
#: longest extra-metadata JSON text [characters]
MAX_EXTRA_CHARS = 4096


def parse_item(name: str, raw: Any, *, what: str | None = None) -> float | str:
    """The value of item ``name`` from outside: a number (text with ``.`` or ``,`` as
    decimal mark, or a number) inside its bounds, or one printable line of text; a
    :class:`ValidationError` naming ``what`` (default: the item) otherwise."""
    item = BY_NAME[name]
    label = what or name
    if item.kind == "float":
        value: Any = raw
        if isinstance(raw, str):
            try:
                value = float(raw.strip().replace(",", "."))
            except ValueError:
                raise ValidationError(f"{label}: expected a number in {item.unit}, "
                                      f"got {raw[:40]!r}") from None
        assert item.bounds is not None
        return check_number(value, item.bounds, label)
    if not isinstance(raw, str):
        raw = str(raw) if isinstance(raw, int | float) and not isinstance(raw, bool) else raw
    problem = text_problem(raw, max_chars=300)
    if problem is not None or not isinstance(raw, str):
        raise ValidationError(f"{label}: {problem or 'expected text'}")
    return raw.strip()


@dataclass(frozen=True)
class RunReport:
    """A run's reporting items (``values``: item name → value, only those known) and its
    ``extra`` metadata (name → text, sorted)."""

    values: tuple[tuple[str, float | str], ...] = ()
    extra: tuple[tuple[str, str], ...] = field(default=())

    @classmethod
    def of(cls, values: Mapping[str, float | str],
           extra: Mapping[str, str] | None = None) -> RunReport:
        """A report from mappings (order does not matter)."""
        return cls(tuple(sorted((k, v) for k, v in values.items() if k in BY_NAME)),
                   tuple(sorted((extra or {}).items())))

    def columns(self) -> dict[str, Any]:
        """The map columns: every item (``None`` where unknown) and ``extra_metadata``
        (:func:`extra_text`, ``None`` when empty)."""
        known = dict(self.values)
        out: dict[str, Any] = {name: known.get(name) for name in NAMES}
        out[EXTRA_COLUMN] = extra_text(dict(self.extra))
        return out

    def over(self, base: RunReport) -> RunReport:
        """This report with ``base``'s values where this one has none."""
        values = dict(base.values) | dict(self.values)
        extra = dict(base.extra) | dict(self.extra)
        return RunReport.of(values, extra)


def extra_text(extra: Mapping[str, str]) -> str | None:
    """Extra metadata as the map keeps it: a JSON object (keys sorted, text values), or
    ``None`` when there is none. A :class:`ValidationError` when it would be longer than
    :data:`MAX_EXTRA_CHARS`."""
    if not extra:
        return None
    text = json.dumps(dict(sorted(extra.items())), ensure_ascii=False)
    if len(text) > MAX_EXTRA_CHARS:
        raise ValidationError(f"extra metadata: {len(text)} characters, expected at most "
                              f"{MAX_EXTRA_CHARS}")
    return text


#: export-header keys (as the readers name them) → item, and how to read the item
_SERIAL = re.compile(r"\bS/?N\s*[:#]?\s*([A-Za-z0-9-]+)")


def from_export(header: Mapping[str, str]) -> dict[str, str]:
    """The reporting items an export's header gives (a reader's ``meta.extra``, the keys
    of :data:`tribopipe.readers.interval.HEADER_FIELDS`): ``device`` ("MCR302 SN81338249;
    FW3.71; …": instrument and serial), ``application`` (the software and its version)
    and ``measuring_date_time``, as Rheoplus writes them in every data series and a
    RheoCompass export where it holds those lines. Nothing else is inferred."""
    out: dict[str, str] = {}
    device = header.get("device")
    if device and text_problem(device, max_chars=300) is None:
        first = device.split(";", 1)[0]
        serial = _SERIAL.search(first)
        model = _SERIAL.sub("", first).strip()
        if model:
            out["instrument"] = model
        if serial:
            out["instrument_serial"] = serial.group(1)
    for key, item in (("application", "software_version"),
                      ("measuring_date_time", "measured_on")):
        value = header.get(key)
        if value and value.strip() and text_problem(value, max_chars=300) is None:
            out[item] = value.strip()
    return out
