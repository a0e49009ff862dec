"""Tables regenerated from the friction map: group statistics, the paper's abstract layout
and the published 7-column FrictionMap schema, as CSV, Markdown or LaTeX.

Layouts (each a DataFrame; units in the column names):

``group``
    :func:`tribopipe.stats.group_statistics`: conditions, then n, mean, std, sem, 95 % CI,
    cv, min, max and values of μ_K and μ_S, the r and QC flags, the run ids.
``abstract``
    like Table 2 of the founding paper: ``pin, disc, pressure_kPa, temperature_C, mu_k``
    (group mean of μ_K, rounded to two decimals).
``paper``
    a compact table to print: ``pin, disc, p [kPa], T [°C]`` (``v [mm/s]`` where the map
    holds several sliding speeds), ``n``, ``μ_S ± U``, ``μ_K ± U`` and ``flags``. U is the
    expanded uncertainty (k = 2) of the group mean (:func:`tribopipe.stats.group_u`),
    rounded the GUM way (:mod:`tribopipe.rounding`); the μ_S column is left out when no
    group holds μ_S. ``n`` counts the runs that have μ_K; ``n (μ_S)`` (CSV ``mu_s_n``),
    shown where some group holds μ_S for fewer runs, those that have μ_S. ``labs``
    (where the groups come from more than one lab) names the labs of each value.
    Flags: ``range > r``, ``labs disagree`` (beyond R, :mod:`tribopipe.stats`),
    ``flagged run``, ``stated u`` (some run carries no budget of its own: its u is the
    stated estimate, :func:`tribopipe.stats.stated_u`), ``n = 1``, ``N reviewed`` (runs a
    reviewer accepted or re-windowed, :mod:`tribopipe.review`). As CSV the value and U
    are separate columns.
``frictionmap``
    one row per included run in the published schema ``pin, disc, contactForce,
    contactPressure, temperature, measurementNo, cof`` (force [N], pressure [kPa],
    temperature [°C], μ_K), so the MATLAB FrictionMap app keeps working. Importing it
    again (:func:`tribopipe.frictionmap.import_records`) gives the same runs.

Markdown and LaTeX are written here (no jinja2 / tabulate needed); numbers there are shown
with four significant digits, in CSV with ten (``frictionmap``: shortest round-trip).
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

from ..config import TEST_METHODS
from ..errors import ExportError
from ..escape import csv_cell, latex_cell, markdown_cell, printable
from ..files import write_text_atomic
from ..frictionmap.published import FRICTIONMAP_COLUMNS
from ..frictionmap.snapshot import MapSnapshot, MapSource, as_snapshot
from ..query import estimate_text
from ..rounding import known_u, round_gum
from ..stats import (
    LABS,
    LABS_DISAGREE,
    NOMINAL_SPEED,
    TEST_METHOD,
    group_keys,
    group_statistics,
    group_u,
    test_methods,
)

if TYPE_CHECKING:
    import pandas as pd

LAYOUTS: tuple[str, ...] = ("group", "abstract", "paper")
FORMATS: tuple[str, ...] = ("csv", "markdown", "latex", "frictionmap")
#: Temperatures closer than this [K] to a --temperature filter value match it.
TEMPERATURE_MATCH_K = 0.005


#: how the tables print a condition: pressure [kPa] to 4 significant digits (11.79, the
#: paper's), temperature [°C] as measured (format "g"), nominal speed [mm/s] to 2
CONDITION_SPECS = {"pressure_kPa": ".4g", "temperature_C": "g", NOMINAL_SPEED: ".2g"}


def condition_text(column: str, value: Any) -> str:
    """A condition value of ``column`` (a key of :data:`CONDITION_SPECS`) as every table
    prints it ('' where missing); the explorer's chips and inputs read the same."""
    return _cell(value, CONDITION_SPECS[column])


#: the group-table columns :func:`group_flags` reads
GROUP_FLAG_FIELDS = ("reviewed", "range_exceeds_r", LABS_DISAGREE, "qc_flagged")


def group_flags(group: Mapping[Any, Any], middle: Sequence[str] = ()) -> list[str]:
    """A group row's flags as every table (and the explorer's QC column) writes them:
    ``range > r``, ``labs disagree``, ``flagged run``, then ``middle`` (the paper layout's
    uncertainty flags), then ``N reviewed``."""
    reviewed = group.get("reviewed") or 0
    return (["range > r"] if group.get("range_exceeds_r") is True else []) + (
        ["labs disagree"] if group.get(LABS_DISAGREE) is True else []) + (
        ["flagged run"] if group.get("qc_flagged") is True else []) + list(middle) + (
        [f"{reviewed} reviewed"] if reviewed else [])


def _select(
    frame: pd.DataFrame,
    pin: Sequence[str] | None,
    disc: Sequence[str] | None,
    temperature_C: Sequence[float] | None,
) -> pd.DataFrame:
    """Rows matching every given filter (materials case-insensitively; a new frame)."""
    import numpy as np

    keep = np.ones(len(frame), dtype=bool)
    for column, wanted in (("pin", pin), ("disc", disc)):
        if wanted:
            names = {w.strip().casefold() for w in wanted}
            keep &= frame[column].astype(str).str.casefold().isin(names).to_numpy()
    if temperature_C:
        t = frame["temperature_C"].to_numpy(dtype=float)
        hit = np.zeros(len(frame), dtype=bool)
        for value in temperature_C:
            hit |= np.abs(t - float(value)) <= TEMPERATURE_MATCH_K
        keep &= hit
    return frame.loc[keep].reset_index(drop=True)


def group_table(
    runs: pd.DataFrame | MapSnapshot,
    *,
    pin: Sequence[str] | None = None,
    disc: Sequence[str] | None = None,
    temperature_C: Sequence[float] | None = None,
    by_speed: bool = False,
) -> pd.DataFrame:
    """The group-statistics table of a map (its rows, or the map opened: its groups,
    :meth:`~tribopipe.frictionmap.snapshot.MapSnapshot.groups`, stored in a map folder),
    filtered after the statistics are computed (so the pooled repeatability s_r and the
    r flags always use the whole map)."""
    groups = (runs.groups(by_speed=by_speed) if isinstance(runs, MapSnapshot)
              else group_statistics(runs, by_speed=by_speed))
    return _select(groups, pin, disc, temperature_C)


def abstract_table(
    runs: pd.DataFrame | MapSnapshot,
    *,
    pin: Sequence[str] | None = None,
    disc: Sequence[str] | None = None,
    temperature_C: Sequence[float] | None = None,
) -> pd.DataFrame:
    """The paper's Table 2 layout: ``pin, disc, pressure_kPa, temperature_C, mu_k`` with
    μ_K the group mean rounded half-up to two decimals, as printed in the paper."""
    groups = group_table(runs, pin=pin, disc=disc, temperature_C=temperature_C)
    condition = ["pin", "disc", "pressure_kPa", "temperature_C"] + (
        [NOMINAL_SPEED] if NOMINAL_SPEED in groups.columns else []) + (
        [TEST_METHOD] if TEST_METHOD in groups.columns else [])
    table = groups.loc[:, condition].copy()
    table["mu_k"] = [round_half_up(v, 2) for v in groups["mu_k_mean"]]
    return table


def _with_u(value: float, u: float, budget: bool, n: int, machine: bool) -> tuple[str, str]:
    """``(value, U)`` texts of a group mean: GUM-rounded where U = 2u is known; for a
    person (``machine`` False) joined as ``value ± U`` in the first text."""
    if not math.isfinite(value):
        return ("", "") if machine else ("–", "")
    expanded = 2.0 * u if known_u(2.0 * u) else None
    if machine:
        if expanded is None:
            return repr(round_half_up(value, 3)), ""
        return round_gum(value, expanded)
    return estimate_text(value, expanded, n), ""


def paper_table(
    runs: pd.DataFrame | MapSnapshot,
    *,
    pin: Sequence[str] | None = None,
    disc: Sequence[str] | None = None,
    temperature_C: Sequence[float] | None = None,
    machine: bool = False,
) -> pd.DataFrame:
    """The ``paper`` layout (module docstring): one row per condition group, every
    number a text rounded for print. ``machine`` (CSV) keeps value and U in separate
    columns (``mu_k``, ``mu_k_U``) and the units in snake-case names."""
    groups = group_table(runs, pin=pin, disc=disc, temperature_C=temperature_C)
    by_speed = NOMINAL_SPEED in groups.columns
    with_mu_s = bool((groups["mu_s_n"] > 0).any()) if len(groups) else False
    names = (("pressure_kPa", "temperature_C", NOMINAL_SPEED) if machine
             else ("p [kPa]", "T [°C]", "v [mm/s]"))
    out: dict[str, list[Any]] = {"pin": list(groups["pin"]), "disc": list(groups["disc"]),
                                 names[0]: [condition_text("pressure_kPa", v)
                                            for v in groups["pressure_kPa"]],
                                 names[1]: [condition_text("temperature_C", v)
                                            for v in groups["temperature_C"]]}
    if by_speed:
        out[names[2]] = [condition_text(NOMINAL_SPEED, v) for v in groups[NOMINAL_SPEED]]
    if TEST_METHOD in groups.columns:  # the map holds several methods: never pooled
        out[TEST_METHOD if machine else "method"] = list(groups[TEST_METHOD])
    if len({lab for v in groups[LABS] for lab in str(v).split(";")}) > 1:
        out["labs"] = [str(v).replace(";", ", ") for v in groups[LABS]]
    out["n"] = [int(v) for v in groups["mu_k_n"]]
    flags: list[list[str]] = [[] for _ in range(len(groups))]
    for q, label in (("mu_s", "μ_S"), ("mu_k", "μ_K")):
        if q == "mu_s" and not with_mu_s:
            continue
        if q == "mu_s" and (groups["mu_s_n"] != groups["mu_k_n"]).any():
            out["mu_s_n" if machine else "n (μ_S)"] = [int(v) for v in groups["mu_s_n"]]
        u, budget = group_u(groups, q)
        texts = [_with_u(float(m), float(uu), bool(b), int(n), machine) for m, uu, b, n in
                 zip(groups[f"{q}_mean"], u, budget, groups[f"{q}_n"], strict=True)]
        if machine:
            out[q] = [t[0] for t in texts]
            out[f"{q}_U"] = [t[1] for t in texts]
        else:
            out[f"{label} ± U"] = [t[0] for t in texts]
        if q == "mu_k":
            for i, (b, n, uu) in enumerate(zip(budget, groups["mu_k_n"], u, strict=True)):
                flags[i] += (["stated u"] if not b else []) + (
                    ["n = 1"] if n < 2 else []) + (
                    ["repeats identical"] if n > 1 and not known_u(2.0 * float(uu)) else [])
    for i, g in enumerate(groups.to_dict(orient="records")):
        flags[i] = group_flags(g, flags[i])
    out["flags"] = [", ".join(f) for f in flags]
    import pandas as pd

    return pd.DataFrame(out)


#: what the paper layout's note says under the table (terminal and Markdown)
PAPER_NOTE = (
    "± U: expanded uncertainty of the group mean (k = 2), from the runs' uncertainty "
    "budgets and the repeat scatter, rounded to two significant digits; an interval that "
    "would reach below 0 is written +U/−value; where several labs measured a condition, U "
    "holds the between-lab component. stated u: some runs carry no uncertainty budget of "
    "their own (imported rows): theirs is the stated estimate of the founding cell at the "
    "run's μ and force; labs disagree: two labs' means differ beyond the critical "
    "difference of R; repeats identical: no scatter to estimate U from."
)


def paper_text(runs: pd.DataFrame | MapSnapshot) -> str:
    """The paper layout as an aligned plain-text table for a terminal (every cell one
    printable line), with :data:`PAPER_NOTE` under it."""
    table = paper_table(runs)
    if table.empty:
        return "no condition group to tabulate\n"
    cells = [[printable(str(c)) for c in table.columns]] + [
        [printable(str(v)) for v in row] for row in table.itertuples(index=False, name=None)]
    widths = [max(len(r[i]) for r in cells) for i in range(len(table.columns))]
    lines = ["  ".join(v.ljust(w) for v, w in zip(r, widths, strict=True)).rstrip()
             for r in cells]
    return "\n".join(lines) + "\n" + PAPER_NOTE + "\n"


def map_paper_text(map_path: MapSource) -> str:
    """:func:`paper_text` of the map at ``map_path`` (excluded runs left out); '' when
    there is no map or no included run (nothing was reduced)."""
    snap = as_snapshot(map_path)
    if not snap.exists:
        return ""
    if snap.empty or snap.groups().empty:  # no included run
        return ""
    return paper_text(snap)


def round_half_up(value: float, decimals: int) -> float:
    """Round as a person would from the printed value: 0.825 → 0.83 (binary ``round``
    gives 0.82 because 0.825 is stored as 0.82499…)."""
    from decimal import ROUND_HALF_UP, Decimal

    if not math.isfinite(value):
        return value
    step = Decimal(1).scaleb(-decimals)
    return float(Decimal(repr(float(value))).quantize(step, rounding=ROUND_HALF_UP))


def frictionmap_table(
    runs: pd.DataFrame,
    *,
    pin: Sequence[str] | None = None,
    disc: Sequence[str] | None = None,
    temperature_C: Sequence[float] | None = None,
) -> pd.DataFrame:
    """The included runs in the published 7-column schema, in map order.

    ``measurementNo`` is the run's repeat number; runs without one are numbered after the
    highest repeat of their condition, in map order.
    """
    import numpy as np
    import pandas as pd

    included = runs.loc[~runs["excluded"].astype(bool)].reset_index(drop=True)
    included = _select(included, pin, disc, temperature_C)
    keys = group_keys(included, by_speed=False)
    # each run's condition (numbered in map order) and repeat (NaN where it has none),
    # as arrays: one pass over the runs, never a frame per condition
    codes = keys.groupby(list(keys.columns), dropna=False, sort=False).ngroup().to_numpy()
    numbers = pd.to_numeric(included["repeat"], errors="coerce").to_numpy(
        dtype=float, na_value=np.nan)
    known = ~np.isnan(numbers)
    highest = np.full(int(codes.max()) + 1 if len(codes) else 0, -np.inf)
    np.maximum.at(highest, codes[known], numbers[known])
    next_free = [int(v) if math.isfinite(v) else 0 for v in highest.tolist()]
    for i in np.flatnonzero(~known).tolist():
        c = int(codes[i])
        next_free[c] += 1
        numbers[i] = float(next_free[c])
    table = pd.DataFrame(
        {
            "pin": included["pin"].to_numpy(dtype=object),
            "disc": included["disc"].to_numpy(dtype=object),
            "contactForce": included["normal_force_N"].to_numpy(dtype=float),
            "contactPressure": included["pressure_kPa"].to_numpy(dtype=float),
            "temperature": included["temperature_C"].to_numpy(dtype=float),
            "measurementNo": numbers,
            "cof": included["mu_k"].to_numpy(dtype=float),
        },
        columns=list(FRICTIONMAP_COLUMNS),
    )
    return table


# --------------------------------------------------------------------------- writers


def _cell(value: Any, spec: str = ".4g") -> str:
    import numpy as np

    if value is None:
        return ""
    if isinstance(value, bool | np.bool_):
        return "yes" if value else "no"
    if isinstance(value, int | np.integer):
        return str(int(value))
    if isinstance(value, float | np.floating):
        return "" if not math.isfinite(value) else format(float(value), spec)
    try:
        import pandas as pd

        if pd.isna(value):
            return ""
    except (TypeError, ValueError):
        pass
    return str(value)


def _numeric(frame: pd.DataFrame, column: str) -> bool:
    import pandas as pd

    dtype = frame[column].dtype
    return bool(pd.api.types.is_numeric_dtype(dtype)) and not pd.api.types.is_bool_dtype(dtype)


def _safe_text_cells(table: pd.DataFrame) -> pd.DataFrame:
    """``table`` with every text cell one printable line that no spreadsheet reads as a
    formula (:func:`~tribopipe.escape.csv_cell`, the OWASP rule); numbers untouched."""
    text_columns = [c for c in table.columns if not _numeric(table, c)
                    and not _is_bool(table[c])]
    if not text_columns:
        return table
    table = table.copy()
    for column in text_columns:
        table[column] = table[column].map(
            lambda v: csv_cell(v) if isinstance(v, str) else v)
    return table


def _is_bool(column: Any) -> bool:
    """True for a boolean column."""
    import pandas as pd

    return bool(pd.api.types.is_bool_dtype(column.dtype))


def to_csv(table: pd.DataFrame, formats: dict[str, str] | None = None, *,
           decimal: str = ".") -> str:
    """CSV text (``\\n`` line ends); floats with ten significant digits, missing as empty,
    text cells safe for spreadsheets (:func:`_safe_text_cells`). ``decimal=","`` writes
    it for a decimal-comma locale: cells separated by ``;``, numbers with a decimal comma
    (a rounded number kept as text, ``0.740``, too), as Excel there reads a CSV.

    ``formats`` is accepted for a uniform writer signature and ignored: CSV is for machines.
    """
    if decimal not in (".", ","):
        raise ExportError(f"unknown decimal mark {decimal!r}; expected '.' or ','")
    safe = _safe_text_cells(table)
    if decimal == ".":
        return safe.to_csv(index=False, lineterminator="\n", float_format="%.10g")
    safe = safe.copy()
    for column in safe.columns:
        if not _numeric(safe, column) and not _is_bool(safe[column]):
            safe[column] = safe[column].map(
                lambda v: v.replace(".", ",") if isinstance(v, str) and _PLAIN_NUMBER.match(v)
                else v)
    return safe.to_csv(index=False, lineterminator="\n", float_format="%.10g", sep=";",
                       decimal=",")


def spreadsheet_csv(table: pd.DataFrame) -> str:
    """CSV text for people who open it in a spreadsheet: :func:`to_csv` (a text cell
    starting with ``=``, ``+``, ``-``, ``@``, a tab or a carriage return gets a leading
    ``'`` so it stays text; numbers, negative ones included, stay numbers), with the
    column names made safe the same way."""
    safe = table.copy(deep=False)
    safe.columns = [csv_cell(str(c)) for c in safe.columns]
    return to_csv(safe)


def frictionmap_csv(table: pd.DataFrame) -> str:
    """CSV text in the published FrictionMap style: floats as shortest round-trip text,
    text cells safe for spreadsheets (read back by
    :func:`tribopipe.frictionmap.published.read_frictionmap_table`, which undoes the
    prefix)."""
    return _safe_text_cells(table).to_csv(index=False, lineterminator="\n")


def _short_values(table: pd.DataFrame) -> pd.DataFrame:
    """For people: ``;``-joined individual values (``mu_k_values``...) with four significant
    digits, like the other floats of a Markdown or LaTeX table."""

    def shorten(text: Any) -> Any:
        if not isinstance(text, str) or not text:
            return text
        try:
            return ";".join(format(float(v), ".4g") for v in text.split(";"))
        except ValueError:
            return text

    columns = [c for c in table.columns if str(c).endswith("_values")]
    if not columns:
        return table
    table = table.copy()
    for column in columns:
        table[column] = table[column].map(shorten)
    return table


def _specs(table: pd.DataFrame, formats: dict[str, str] | None) -> list[str]:
    formats = formats or {}
    return [formats.get(str(c), ".4g") for c in table.columns]


def to_markdown(table: pd.DataFrame, formats: dict[str, str] | None = None) -> str:
    """A GitHub-flavoured Markdown table; numeric columns right-aligned. Floats use
    ``formats[column]`` (a format spec) or four significant digits. Every cell is one
    inert cell (:func:`~tribopipe.escape.markdown_cell`: no raw HTML, no broken row)."""
    table = _short_values(table)
    header = [str(c) for c in table.columns]
    align = ["---:" if _numeric(table, c) else "---" for c in table.columns]

    esc = markdown_cell

    specs = _specs(table, formats)
    lines = ["| " + " | ".join(esc(h) for h in header) + " |", "| " + " | ".join(align) + " |"]
    for row in table.itertuples(index=False, name=None):
        cells = (esc(_cell(v, f)) for v, f in zip(row, specs, strict=True))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


#: the packages a LaTeX table needs in the document's preamble (its first lines say so)
LATEX_PACKAGES: tuple[str, ...] = ("booktabs", "siunitx")
_PLAIN_NUMBER = re.compile(r"^(-?)(\d+)(?:\.(\d+))?$")


def latex_header(what: str) -> list[str]:
    """The comment lines that open every LaTeX table: what it is and what it needs."""
    return [f"% {latex_comment(what)}",
            "% Needs in the preamble: " + " ".join(f"\\usepackage{{{p}}}"
                                                  for p in LATEX_PACKAGES),
            "% Put it in a table with \\input{this file}."]


def latex_comment(text: str) -> str:
    """One line of inert text for a LaTeX comment (a name in it is escaped as in a cell,
    so no newline ends the comment and no ``%`` or ``\\`` acts)."""
    return latex_cell(text)


def _number_column(cells: Sequence[str]) -> str | None:
    """The siunitx ``S`` column spec aligning ``cells`` on the decimal point
    (``S[table-format=-2.3]``), or ``None`` when a cell is not a plain decimal number."""
    ints, decs, sign = 1, 0, ""
    seen = False
    for cell in cells:
        if cell == "":
            continue
        m = _PLAIN_NUMBER.match(cell)
        if m is None:
            return None
        seen = True
        sign = sign or m.group(1)
        ints = max(ints, len(m.group(2)))
        decs = max(decs, len(m.group(3) or ""))
    if not seen:
        return None
    return f"S[table-format={sign}{ints}.{decs}]" if decs else f"S[table-format={sign}{ints}]"


def to_latex(table: pd.DataFrame, formats: dict[str, str] | None = None, *,
             what: str = "tribopipe friction-map table") -> str:
    """A booktabs ``tabular`` that compiles as written with the packages its first lines
    name (:data:`LATEX_PACKAGES`): numeric columns aligned on the decimal point
    (siunitx ``S``; ``r`` where a cell is not a plain decimal), every text cell escaped
    (:func:`~tribopipe.escape.latex_cell`), floats formatted as in :func:`to_markdown`."""
    table = _short_values(table)
    specs = _specs(table, formats)
    rows = [[_cell(v, f) for v, f in zip(row, specs, strict=True)]
            for row in table.itertuples(index=False, name=None)]
    columns: list[str] = []
    for i, c in enumerate(table.columns):
        number = _number_column([r[i] for r in rows]) if _numeric(table, c) else None
        columns.append(number or ("r" if _numeric(table, c) else "l"))
    head = [("{" + latex_cell(str(c)) + "}") if spec.startswith("S") else latex_cell(str(c))
            for c, spec in zip(table.columns, columns, strict=True)]
    lines = [*latex_header(what),
             f"\\begin{{tabular}}{{{''.join(columns)}}}",
             "\\toprule",
             " & ".join(head) + " \\\\",
             "\\midrule"]
    for row in rows:
        cells = (latex_cell(v) if not spec.startswith("S") or v == "" else v
                 for v, spec in zip(row, columns, strict=True))
        lines.append(" & ".join(cells) + " \\\\")
    lines += ["\\bottomrule", "\\end{tabular}"]
    return "\n".join(lines) + "\n"


def runs_of_methods(runs: pd.DataFrame, methods: Sequence[str]) -> pd.DataFrame:
    """The runs measured with one of ``methods`` (a row naming none was measured on the
    rheometer cell, :func:`tribopipe.stats.test_methods`); :class:`ExportError` naming the
    known methods for an unknown one."""
    unknown = [m for m in methods if m not in TEST_METHODS]
    if unknown:
        raise ExportError(f"unknown test method {printable(unknown[0])[:60]!r}; expected one "
                          "of " + ", ".join(repr(m) for m in TEST_METHODS))
    return runs.loc[[m in set(methods) for m in test_methods(runs)]]


#: the paper layout's column heads in LaTeX (the units upright, siunitx's °C)
_PAPER_LATEX_HEADS = {"pin": "pin", "disc": "disc", "pressure_kPa": "{$p$ [kPa]}",
                      "temperature_C": "{$T$ [\\si{\\degreeCelsius}]}",
                      NOMINAL_SPEED: "{$v$ [mm/s]}", "n": "{$n$}", "flags": "flags",
                      TEST_METHOD: "method"}


def _pm_cells(value: str, expanded: str) -> tuple[str, str, str]:
    """A group mean for the LaTeX paper table as three cells: value, ``$\\pm$``, U
    (:func:`tribopipe.rounding.plus_minus`'s rule: bounded at zero where value − U < 0,
    written +U/−value as a superscript and subscript; no U: the value alone)."""
    from decimal import Decimal

    if value == "":
        return "{--}", "", ""
    if expanded == "":
        return value, "", ""
    if Decimal(value) < Decimal(expanded):
        return value, "", f"{{$^{{+{expanded}}}_{{-{value}}}$}}"
    return value, "$\\pm$", expanded


def paper_latex(runs: pd.DataFrame | MapSnapshot, **filters: Any) -> str:
    """The paper layout as a LaTeX table that compiles as written (:func:`to_latex`'s
    header): μ_S and μ_K each as value, ±, U in three columns, the value and U aligned on
    the decimal point, and the ± U note under the table."""
    table = paper_table(runs, machine=True, **filters)
    plain = [c for c in table.columns if c not in ("mu_s", "mu_s_U", "mu_k", "mu_k_U")]
    quantities = [q for q in ("mu_s", "mu_k") if q in table.columns]
    spec: list[str] = []
    head: list[str] = []
    body: list[list[str]] = [[] for _ in range(len(table))]
    for column in plain[:-1]:  # the conditions and n, then the coefficients, then flags
        cells = [_cell(v, "g") for v in table[column]]
        spec.append(_number_column(cells) or "l")
        head.append(_PAPER_LATEX_HEADS.get(column, latex_cell(str(column))))
        for i, cell in enumerate(cells):
            body[i].append(cell if spec[-1].startswith("S") else latex_cell(cell))
    for q in quantities:
        triples = [_pm_cells(str(v), str(u)) for v, u in zip(table[q], table[f"{q}_U"],
                                                             strict=True)]
        values = [t[0] for t in triples if not t[0].startswith("{")]
        errors = [t[2] for t in triples if not t[2].startswith("{")]
        spec += [_number_column(values) or "r", "@{\\,}c@{\\,}",
                 _number_column(errors) or "l"]
        symbol = "S" if q == "mu_s" else "K"
        head.append(f"\\multicolumn{{3}}{{c}}{{$\\mu_{symbol} \\pm U$}}")
        for i, t in enumerate(triples):
            body[i] += list(t)
    spec.append("l")
    head.append("flags")
    for i, flags in enumerate(table["flags"]):
        body[i].append(latex_cell(str(flags)))
    lines = [*latex_header("tribopipe friction-map table, paper layout"),
             f"\\begin{{tabular}}{{{''.join(spec)}}}", "\\toprule",
             " & ".join(head) + " \\\\", "\\midrule",
             *(" & ".join(row) + " \\\\" for row in body),
             "\\bottomrule", "\\end{tabular}",
             "\\par\\smallskip",
             "{\\footnotesize " + _latex_symbols(latex_cell(PAPER_NOTE)) + "\\par}"]
    return "\n".join(lines) + "\n"


def render_table(
    runs: pd.DataFrame | MapSnapshot,
    *,
    fmt: str = "csv",
    layout: str = "group",
    pin: Sequence[str] | None = None,
    disc: Sequence[str] | None = None,
    temperature_C: Sequence[float] | None = None,
    by_speed: bool = False,
    decimal: str = ".",
    method: Sequence[str] | None = None,
) -> str:
    """A table of the map as text: ``fmt`` one of :data:`FORMATS`, ``layout`` one of
    :data:`LAYOUTS` (``frictionmap`` has its own layout); ``decimal`` the decimal mark of a
    CSV (``","``: for a decimal-comma locale, :func:`to_csv`); ``method`` keeps the runs of
    these test methods only (:data:`tribopipe.config.TEST_METHODS`). Raises
    :class:`ExportError` for an unknown format/layout/method or when no row matches the
    filters."""
    if decimal != "." and fmt != "csv":
        raise ExportError(f"a decimal comma is for --format csv, not {fmt}",
                          hint="drop --decimal")
    if isinstance(runs, MapSnapshot) and (method or fmt == "frictionmap"):
        runs = runs.runs  # these read the runs themselves
    if method:
        assert not isinstance(runs, MapSnapshot)
        runs = runs_of_methods(runs, method)
    if fmt not in FORMATS:
        raise ExportError(f"unknown table format {fmt!r}; expected one of {', '.join(FORMATS)}")
    if layout not in LAYOUTS:
        raise ExportError(f"unknown table layout {layout!r}; expected one of {', '.join(LAYOUTS)}")
    filters: dict[str, Any] = {"pin": pin, "disc": disc, "temperature_C": temperature_C}
    if fmt == "frictionmap":
        if layout != "group" or by_speed:
            raise ExportError(
                "the frictionmap format has its own 7-column layout",
                hint="drop --layout / --by-speed",
            )
        assert not isinstance(runs, MapSnapshot)
        table = frictionmap_table(runs, **filters)
    elif layout == "abstract":
        if by_speed:
            raise ExportError("the abstract layout does not split by speed", hint="drop --by-speed")
        table = abstract_table(runs, **filters)
    elif layout == "paper":
        if by_speed:
            raise ExportError("the paper layout splits by speed where the map holds several",
                              hint="drop --by-speed")
        if fmt == "latex":
            if paper_table(runs, **filters).empty:
                table = paper_table(runs, **filters)  # the "no rows" error below
            else:
                return paper_latex(runs, **filters)
        table = paper_table(runs, machine=fmt == "csv", **filters)
    else:
        table = group_table(runs, by_speed=by_speed, **filters)
    if table.empty:
        given = ", ".join(f"{k}={list(v)}" for k, v in {**filters, "method": method}.items()
                          if v) or "no filter"
        raise ExportError(
            f"no rows to tabulate ({given}; the map holds "
            f"{runs.n_runs if isinstance(runs, MapSnapshot) else len(runs)} runs)",
            hint="check `tribopipe map show` for the pins, discs and temperatures",
        )
    if fmt == "frictionmap":
        return frictionmap_csv(table)
    # The paper prints μ_K with two decimals; keep "0.30", not "0.3".
    formats = {"mu_k": ".2f"} if layout == "abstract" else None
    if fmt == "csv":
        return to_csv(table, formats, decimal=decimal)
    text = {"markdown": to_markdown, "latex": to_latex}[fmt](table, formats)
    if layout == "paper" and fmt == "markdown":
        text += "\n" + markdown_cell(PAPER_NOTE) + "\n"
    return text


def _latex_symbols(text: str) -> str:
    """The paper layout's symbols in LaTeX math (after escaping: nothing else is touched)."""
    for plain, latex in ((r"\ensuremath{\mu}\_S", r"$\mu_S$"),
                         (r"\ensuremath{\mu}\_K", r"$\mu_K$"),
                         (r"\textdegree{}C", r"\si{\degreeCelsius}")):
        text = text.replace(plain, latex)
    return text


def export_table(
    map_path: MapSource,
    output: str | os.PathLike[str] | None = None,
    **options: Any,
) -> str:
    """Read the map at ``map_path``, render a table (options of :func:`render_table`) and,
    when ``output`` is given, write it there (UTF-8). Returns the text."""
    snap = as_snapshot(map_path)
    if not snap.exists:
        raise ExportError("friction map not found", path=snap.path, hint="pass --map PATH")
    text = render_table(snap, **options)
    if output is not None:

        write_text_atomic(output, text, newline="")
    return text
