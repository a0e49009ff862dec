"""What a trace plot says of a run: its conditions, its readings and its flags.

:class:`TraceConditions` are the run's file and nominal conditions (the header's first two
lines), :class:`TraceMarks` what the reduction read and flagged (the marks on the μ panel
and the header's last two lines). Plain data and text; nothing here draws. A stored run is
read through :class:`StoredRun`, the fields of a map row a plot needs: the map's typed
row (``tribopipe.frictionmap.schema.MapRow``, a layer above) has them all.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

from ..numeric import finite_or_none, is_finite
from ..rounding import known_u, plus_minus


class StoredRun(Protocol):
    """What a trace plot reads of a stored run (a map row): its file and nominal
    conditions (force [N], pressure [kPa] per pin, temperature [°C], repeat), its readings
    (μ_S at its distance [mm], μ_K over its window [mm], their standard uncertainties),
    its flags (the map's ``;``-joined text) and its review decision; ``None`` is unknown."""

    @property
    def source_file(self) -> str | None: ...
    @property
    def pin(self) -> str | None: ...
    @property
    def disc(self) -> str | None: ...
    @property
    def normal_force_N(self) -> float | None: ...
    @property
    def pressure_kPa(self) -> float | None: ...
    @property
    def temperature_C(self) -> float | None: ...
    @property
    def repeat(self) -> int | None: ...
    @property
    def mu_s(self) -> float | None: ...
    @property
    def mu_s_distance_mm(self) -> float | None: ...
    @property
    def mu_k(self) -> float | None: ...
    @property
    def mu_k_window_start_mm(self) -> float | None: ...
    @property
    def mu_k_window_end_mm(self) -> float | None: ...
    @property
    def u_mu_s(self) -> float | None: ...
    @property
    def u_mu_k(self) -> float | None: ...
    @property
    def flags(self) -> str | None: ...
    @property
    def review(self) -> str | None: ...


@dataclass(frozen=True)
class TraceConditions:
    """What a trace plot's header says of a run: its source and nominal conditions.

    ``normal_force_N`` is the nominal total normal force [N] (also drawn on the force
    panel), ``pressure_kPa`` the nominal contact pressure per pin [kPa], ``temperature_C``
    the nominal temperature [°C]; ``None`` means unknown (left out of the header).
    """

    source: str | None = None
    pin: str | None = None
    disc: str | None = None
    normal_force_N: float | None = None
    pressure_kPa: float | None = None
    temperature_C: float | None = None
    repeat: int | None = None

    @classmethod
    def from_row(cls, row: StoredRun) -> TraceConditions:
        """The conditions of a stored run (a map row: ``source_file, pin, disc,
        normal_force_N, pressure_kPa, temperature_C, repeat``; ``None`` is unknown)."""
        return cls(source=_text_or_none(row.source_file),
                   pin=_text_or_none(row.pin), disc=_text_or_none(row.disc),
                   normal_force_N=finite_or_none(row.normal_force_N),
                   pressure_kPa=finite_or_none(row.pressure_kPa),
                   temperature_C=finite_or_none(row.temperature_C),
                   repeat=row.repeat)

    def line(self) -> str:
        """One line: ``pin on disc · F 3 N (35.37 kPa per pin) · 20 °C · repeat 2``."""
        parts = []
        if self.pin or self.disc:
            parts.append(f"{self.pin or 'pin ?'} on {self.disc or 'disc ?'}")
        if self.normal_force_N is not None:
            force = f"F {self.normal_force_N:g} N"
            if self.pressure_kPa is not None:
                force += f" ({self.pressure_kPa:.4g} kPa per pin)"
            parts.append(force)
        elif self.pressure_kPa is not None:
            parts.append(f"{self.pressure_kPa:.4g} kPa per pin")
        if self.temperature_C is not None:
            parts.append(f"{self.temperature_C:g} °C")
        if self.repeat is not None:
            parts.append(f"repeat {self.repeat}")
        return " · ".join(parts) if parts else "conditions unknown"


def _text_or_none(value: Any) -> str | None:
    """``str(value)`` for a present text; ``None`` for a missing one (None, NaN, '')."""
    if value is None or (isinstance(value, float) and value != value):
        return None
    return str(value) or None


@dataclass(frozen=True)
class TraceMarks:
    """The readings a trace plot marks: μ_S at its distance [mm], μ_K over its window
    ``(start, end)`` [mm], and the run's flags; non-finite values are not drawn."""

    mu_s: float | None
    mu_s_distance_mm: float | None
    mu_k: float | None
    mu_k_window_mm: tuple[Any, Any] | None
    flags: tuple[str, ...] = ()
    #: standard uncertainties (k = 1) of μ_S and μ_K when known; drawn as U = 2u
    u_mu_s: float | None = None
    u_mu_k: float | None = None
    #: a reviewer's decision on the run (``accept``, ``exclude``, ``window``;
    #: :mod:`tribopipe.review`): the readings line says so
    review: str | None = None

    @property
    def peak_at_limit(self) -> bool:
        """μ_S was read on a limit of its search (flag ``peak_at_search_limit``)."""
        return "peak_at_search_limit" in self.flags

    @property
    def window_at_end(self) -> bool:
        """The μ_K window ends with the trace (flag ``plateau_at_trace_end``)."""
        return "plateau_at_trace_end" in self.flags

    def expanded(self, u: float | None) -> float | None:
        """U = 2u (k = 2) of a finite standard uncertainty, else ``None``."""
        finite = finite_or_none(u)
        return None if finite is None else 2.0 * finite

    @property
    def window(self) -> tuple[float, float] | None:
        """The μ_K window ``(start, end)`` [mm] when both ends are finite."""
        w = self.mu_k_window_mm
        if w is None or not all(is_finite(v) for v in w):
            return None
        return float(w[0]), float(w[1])

    def line(self) -> str:
        """One line of what was read: ``μ_S = 0.702 ± 0.021 (k = 2) at 0.0987 mm · μ_K =
        0.480 over 0.251–8.39 mm`` (``± U`` where an uncertainty is known, rounded the GUM
        way by :func:`tribopipe.rounding.plus_minus`; ``not found`` for a missing
        reading)."""
        if is_finite(self.mu_s):
            static = f"μ_S = {float(self.mu_s):.3f}"  # type: ignore[arg-type]
            u_s = self.expanded(self.u_mu_s)
            if u_s is not None and known_u(u_s):
                static = f"μ_S = {plus_minus(float(self.mu_s), u_s)} (k = 2)"  # type: ignore[arg-type]
            if is_finite(self.mu_s_distance_mm):
                static += f" at {float(self.mu_s_distance_mm):.3g} mm"  # type: ignore[arg-type]
        else:
            static = "μ_S not found"
        if is_finite(self.mu_k):
            kinetic = f"μ_K = {float(self.mu_k):.3f}"  # type: ignore[arg-type]
            u_k = self.expanded(self.u_mu_k)
            if u_k is not None and known_u(u_k):
                kinetic = f"μ_K = {plus_minus(float(self.mu_k), u_k)} (k = 2)"  # type: ignore[arg-type]
            if self.window is not None:
                kinetic += f" over {self.window[0]:.3g}–{self.window[1]:.3g} mm"
        else:
            kinetic = "μ_K not found"
        reviewed = f" · reviewed: {self.review}" if self.review else ""
        return f"{static} · {kinetic}{reviewed}"


#: Header lines are cut to this many characters (a file name can be any length).
HEADER_CHARS = 110


def shorten(text: str, limit: int = HEADER_CHARS) -> str:
    """``text`` cut in the middle with an ellipsis when it is longer than ``limit``."""
    if len(text) <= limit:
        return text
    half = (limit - 1) // 2
    return text[:half] + "…" + text[len(text) - (limit - 1 - half):]
