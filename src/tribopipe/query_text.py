"""A query's result as text for a person: the lines ``tribopipe query`` prints.

The estimation is :mod:`tribopipe.query`'s (:func:`~tribopipe.query.query`, its
:class:`~tribopipe.query.QueryResult`); this room only words it: the condition, the test
method, μ_K and μ_S with U (k = 2) and what U holds, the groups used with their
weights, the measured range and the notes.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .config import InstrumentConfig
    from .query import Estimate, QueryResult


def format_result(res: QueryResult, normal_force_N: float | None = None,
                  instrument: InstrumentConfig | None = None) -> str:
    """A short human-readable report of a query (several lines, no trailing newline);
    ``normal_force_N`` and ``instrument`` say the force the pressure was converted from."""

    def est_text(name: str, est: Estimate | None) -> list[str]:
        """The lines of an estimate: value ± U (k = 2), then what U holds and the repeats'
        interval in its own line; or 'unknown'."""
        if est is None:
            return [f"{name} = unknown (no group of this pair holds it)"]
        head = f"{name} = {est.text()}" + ("" if est.expanded is None else " (U, k = 2)")
        groups_u = ("unknown" if est.u_groups is None else f"{est.u_groups:.2g}"
                    + ("" if est.budgets_known
                       else " (with the stated u of runs without a budget)"))
        lines = [head, f"  U = 2·√(u_groups² + u_interp²): u_groups = {groups_u}, "
                       f"u_interp = {est.u_interpolation:.2g}"]
        if est.expanded is not None and est.lower is not None:
            lines[-1] += f"; interval [{est.lower:.3g}, {est.value + est.expanded:.3g}]"
        if est.uncertainty is not None:
            lines.append(f"  repeats' 95 % CI half-width (interpolated): {est.uncertainty:.3f}")
        return lines

    t = "" if res.temperature_C is None else f", {res.temperature_C:g} °C"
    if len(res.speeds_mm_s) > 1 and res.speed_mm_s is not None:
        t += f", {res.speed_mm_s:g} mm/s"
    force = ""
    if normal_force_N is not None and instrument is not None:
        force = (f" ({normal_force_N:g} N on {instrument.n_pins} pin(s) of radius "
                 f"{instrument.pin_radius_mm:g} mm)")
    lines = [
        f"{res.pin} on {res.disc} at {res.pressure_kPa:.4g} kPa{force}{t}",
        f"  test method: {res.method}",
        *("  " + line for line in est_text("mu_k", res.mu_k)),
        *("  " + line for line in est_text("mu_s", res.mu_s)),
        "  from measured groups (pressure, temperature, mean, n, weight):",
    ]
    for u in res.mu_k.used:
        t_u = "?" if u.temperature_C is None else f"{u.temperature_C:g} °C"
        lines.append(
            f"    {u.pressure_kPa:g} kPa, {t_u}, {u.mean:.3f}, n={u.n}, w={u.weight:.3f}"
        )
    lo, hi = res.pressure_range_kPa
    temps = ", ".join(f"{v:g}" for v in res.temperatures_C) or "unknown"
    lines.append(f"  measured: {lo:g}–{hi:g} kPa at {temps} °C"
                 + (f", {', '.join(f'{v:g}' for v in res.speeds_mm_s)} mm/s"
                    if len(res.speeds_mm_s) > 1 else ""))
    lines.append(f"  clamped: {'yes' if res.clamped else 'no'}")
    lines += [f"  note: {n}" for n in res.notes]
    return "\n".join(lines)
