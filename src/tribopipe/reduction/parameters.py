"""What a reduced run records besides its readings (``ReductionResult.parameters``).

The method's settings it was reduced with (the :class:`~tribopipe.config.ReductionParams`
of its config, the one place that defines them), the diagnostics of its detection (one
class per method: :class:`RotaryParameters` for a run over a sliding path,
:class:`ReciprocatingParameters` for a linear reciprocating run, ASTM G133), the
instrument's side of it (:class:`InstrumentSide`) and its uncertainty budgets
(:class:`Budgets`). Every field is typed, so a misspelt diagnostic is a type error;
:meth:`RunParameters.to_json` is the run summary's flat ``parameters`` object, the one
place the names below become JSON keys. Each field's meaning is in the method's
description (:mod:`tribopipe.reduction`).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

from ..config import ReductionParams
from .manual import TraceTerms
from .reciprocating import Cycle
from .uncertainty import COVERAGE_FACTOR, Budget


@dataclass(frozen=True)
class Budgets:
    """A run's uncertainty budgets (GUM, k = 1): ``mu_k`` and ``mu_s`` source by source,
    the plateau's integrated autocorrelation time [samples], the standard uncertainty of
    the torque zero [N·m] and of the friction radius [mm] (``None`` for a reciprocating
    run, whose cycles hold no radius), and the terms a reviewer's window is read with
    (``(relative, absolute)``, :func:`~tribopipe.reduction.uncertainty.budget_terms`;
    ``None`` for a reciprocating run, whose μ_K is read over cycles, not a window of the
    trace)."""

    mu_k: Budget
    mu_s: Budget
    plateau_tau_int_samples: float
    torque_offset_u_Nm: float
    friction_radius_u_mm: float | None = None
    terms: tuple[float, float] | None = None

    #: the coverage factor of the budgets' standard uncertainties
    k = 1

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "mu_k": dict(self.mu_k), "mu_s": dict(self.mu_s), "k": self.k,
            "coverage_factor_expanded": COVERAGE_FACTOR,
            "plateau_tau_int_samples": self.plateau_tau_int_samples,
            "torque_offset_u_Nm": self.torque_offset_u_Nm,
        }
        if self.friction_radius_u_mm is not None:
            out["friction_radius_u_mm"] = self.friction_radius_u_mm
        if self.terms is not None:
            out["terms"] = {"relative": self.terms[0], "absolute": self.terms[1]}
        return out


@dataclass(frozen=True)
class InstrumentSide:
    """The instrument's side of a run: its test method and tangential channel, where the
    normal force came from (words), the zero's refused load fraction and second zero
    (``None`` without them), the samples of an end stop trimmed and the path they held
    [mm], one revolution's path [mm] (``None`` off a rotating cell) and whether the
    plateau's oscillation is locked to the rotation (``run_out``)."""

    test_method: str
    tangential_channel: str
    normal_force_source: str
    zero_load_fraction: float | None
    zero_second: float | None
    end_stop_samples: int
    end_stop_trimmed_mm: float
    revolution_mm: float | None
    run_out: bool


@dataclass(frozen=True, kw_only=True)
class RunParameters:
    """What every reduced run records: the method's ``settings``, the ``instrument``'s
    side, the ``uncertainty`` budgets, and the diagnostics both methods have — where the
    sliding distance came from, the zero subtracted [N·m, or N for a friction force] and
    where it came from, whether the plateau settled, the raw static peak, its prominence,
    the normal force's coefficient of variation and the samples read."""

    settings: ReductionParams
    instrument: InstrumentSide
    uncertainty: Budgets
    distance_source: str
    torque_offset_Nm: float
    torque_offset_source: str
    plateau_settled: bool
    mu_s_peak_raw: float
    static_prominence: float
    normal_force_cv: float
    n_samples: int

    def _diagnostics(self) -> dict[str, Any]:
        """This method's own diagnostics as JSON (in the order they are written)."""
        raise NotImplementedError

    def to_json(self) -> dict[str, Any]:
        """The flat JSON object of a run's summary (``parameters``): the settings, the
        diagnostics, ``uncertainty``, then the instrument's side."""
        out: dict[str, Any] = asdict(self.settings)
        out.update(self._diagnostics())
        out["uncertainty"] = self.uncertainty.to_json()
        out.update(asdict(self.instrument))
        return out

    def trace_terms(self) -> TraceTerms | None:
        """What a reviewer's window over this run's trace is read with
        (:mod:`tribopipe.reduction.manual`); ``None`` where the run has no window terms."""
        terms = self.uncertainty.terms
        if terms is None:
            return None
        return TraceTerms(terms[0], terms[1], self.settings.min_plateau_samples,
                          self.settings.peak_window_mm)


@dataclass(frozen=True, kw_only=True)
class RotaryParameters(RunParameters):
    """A run over one sliding path (a rheometer's or a rotary tribometer's rotation, a
    sled's pull): the instrument's geometry (contact threshold [N], friction radius [mm],
    pins and their radius [mm]), the signs read from the run, and the detection's
    diagnostics (noise, settling tolerance, drift's standard error [1/mm], the peak's
    place [mm] and the search's end [mm], the stick-slip test's line ratio, threshold,
    standard deviation and period [mm], the samples dropped, in contact and in the
    plateau)."""

    contact_threshold_N: float
    friction_radius_mm: float
    n_pins: int
    pin_radius_mm: float
    torque_sign: float
    normal_force_sign: float
    noise_std: float
    settle_tolerance: float
    plateau_drift_se_per_mm: float | None
    mu_s_peak_distance_mm: float
    mu_s_search_end_mm: float
    stick_slip_line_ratio: float
    stick_slip_line_threshold: float
    stick_slip_std: float
    stick_slip_period_mm: float | None
    n_dropped_incomplete: int
    n_in_contact: int
    n_plateau: int

    def _diagnostics(self) -> dict[str, Any]:
        return {
            "contact_threshold_N": self.contact_threshold_N,
            "friction_radius_mm": self.friction_radius_mm,
            "n_pins": self.n_pins,
            "pin_radius_mm": self.pin_radius_mm,
            "distance_source": self.distance_source,
            "torque_offset_Nm": self.torque_offset_Nm,
            "torque_offset_source": self.torque_offset_source,
            "torque_sign": self.torque_sign,
            "normal_force_sign": self.normal_force_sign,
            "noise_std": self.noise_std,
            "settle_tolerance": self.settle_tolerance,
            "plateau_settled": self.plateau_settled,
            "plateau_drift_se_per_mm": self.plateau_drift_se_per_mm,
            "mu_s_peak_raw": self.mu_s_peak_raw,
            "mu_s_peak_distance_mm": self.mu_s_peak_distance_mm,
            "static_prominence": self.static_prominence,
            "mu_s_search_end_mm": self.mu_s_search_end_mm,
            "stick_slip_line_ratio": self.stick_slip_line_ratio,
            "stick_slip_line_threshold": self.stick_slip_line_threshold,
            "stick_slip_std": self.stick_slip_std,
            "stick_slip_period_mm": self.stick_slip_period_mm,
            "normal_force_cv": self.normal_force_cv,
            "n_samples": self.n_samples,
            "n_dropped_incomplete": self.n_dropped_incomplete,
            "n_in_contact": self.n_in_contact,
            "n_plateau": self.n_plateau,
        }


@dataclass(frozen=True, kw_only=True)
class ReciprocatingParameters(RunParameters):
    """A linear reciprocating run (ASTM G133): the instrument's sign convention, the full
    strokes and cycles used, the median stroke [mm], μ_K's forward and backward averages
    over the plateau's cycles, every cycle, and the plateau's first cycle (from 1)."""

    friction_sign: float
    n_strokes: int
    n_cycles: int
    stroke_length_mm: float
    mu_k_forward: float
    mu_k_backward: float
    cycles: tuple[Cycle, ...]
    plateau_first_cycle: int

    def _diagnostics(self) -> dict[str, Any]:
        return {
            "distance_source": self.distance_source,
            "torque_offset_Nm": self.torque_offset_Nm,
            "torque_offset_source": self.torque_offset_source,
            "friction_sign": self.friction_sign,
            "n_strokes": self.n_strokes,
            "n_cycles": self.n_cycles,
            "stroke_length_mm": self.stroke_length_mm,
            "mu_k_forward": self.mu_k_forward,
            "mu_k_backward": self.mu_k_backward,
            "cycles": [c.to_json() for c in self.cycles],
            "plateau_first_cycle": self.plateau_first_cycle,
            "plateau_settled": self.plateau_settled,
            "mu_s_peak_raw": self.mu_s_peak_raw,
            "static_prominence": self.static_prominence,
            "normal_force_cv": self.normal_force_cv,
            "n_samples": self.n_samples,
        }
