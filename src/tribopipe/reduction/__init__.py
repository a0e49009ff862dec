"""The reduction method: a friction run's COF trace, μ_S and μ_K with their evidence.

This docstring is the one description of the method; the modules of the package carry
it out:

* :mod:`~tribopipe.reduction.intervals`: the friction interval of an export, its zero
  offset, the rest before and after sliding and a stop at the end;
* :mod:`~tribopipe.reduction.signals`: the signal filters (NumPy, no SciPy);
* :mod:`~tribopipe.reduction.detection`: the detection steps 1–7 below;
* :mod:`~tribopipe.reduction.uncertainty`: each run's uncertainty budget (GUM, k = 1);
* :mod:`~tribopipe.reduction.reciprocating`: a linear reciprocating run's strokes and
  cycles;
* :mod:`~tribopipe.reduction.reduce`: one run end to end (``reduce_measurement``), the
  flags and the ``ReductionResult``.

Physics (formulas in :mod:`tribopipe.physics`; ``n_pins`` pins of radius ``r``, R_eff)
-----------------------------------------------------------------------------------------
* contact pressure per pin ``p = (F_N / n_pins) / (π r²)``: N/mm² = MPa, ×1000 → kPa
  (1 N on three pins of r = 3 mm → 11.79 kPa);
* friction force ``F_R = M / R_eff`` (M in N·m, R_eff in m), COF ``μ = F_R / F_N``;
* sliding distance ``s = φ · R_eff`` from the deflection angle (rad × mm → mm); else the
  integral of the rotational speed; else nominal speed × time.

Instruments (``InstrumentConfig.test_method``). The rheometer (``"rheometer
pin-on-disc"``) measures a torque M at R_eff. A force-based instrument (``"sled D1894"``,
``"linear reciprocating"``, ``"rotary pin-on-disc"``) measures the friction force F itself
(``friction_force_N``); it is read as a torque F·1 m at an exact lever of 1 m, so one set
of formulas and one uncertainty budget serve both (the force channel's own calibration,
resolution and unknown zero in the torque's place, no friction-radius term). A sled has no
normal-force sensor: a run without a normal-force column takes F_N = m·g from
``sled_mass_g`` (or ``sled_weight_N``), stated in ``parameters.instrument.normal_force_source``.
Sliding distance, in this order: a position, crosshead or distance column (counted along
the direction of travel); an angle or rotational speed at the friction radius (a rotary
tribometer's wear track); a linear instrument's ``nominal_speed_mm_s`` × time; the
nominal rpm × time.

Windows scale with the run. Every window and search bound is a distance along the sliding
path [mm] (``*_mm``), a number of samples, or a probability, never a time: an instrument
file states them for its own run — a rheometer's hundredths of a millimetre, a sled's
centimetres, a tribometer's metres (bounds up to 1 km) — and a window wider than the run
acts as the whole run, so none allocates beyond the run's own length.

Signs. The rotation direction decides the signs of angle, speed and torque. Distance is
counted along the direction of travel (``s`` grows from 0); the friction force takes the
sign that makes the median offset-corrected torque of the sliding part positive. We use
that sign, not ``|M|``, so that noise around zero is not rectified into a positive bias.
A negative median normal force (compression written as negative) is flipped likewise.

Zero offset. The zero of the tangential channel (torque or friction force) is read only
where the instrument is known unloaded. ``InstrumentConfig.zero_offset`` (or ``tribopipe
reduce --zero``): a number is used as given; ``"off"`` takes 0; ``"auto"`` (default)
estimates it (:func:`.intervals.robust_mean`: efficient on noise, deaf to spikes) from,
in this order, the set-up interval before the friction interval (attached by
:func:`.intervals.friction_intervals` as ``meta.torque_offset``) and the samples before
the first movement (at least ``ReductionParams.offset_min_samples``). Samples at rest may
already carry a tangential load — a sled's string pulled taut before the record started,
pins pre-sheared by the set-up: an estimate whose level exceeds
``zero_load_max_fraction`` of the sliding level above it
(:func:`.intervals.load_fraction`: a transducer's offset is small beside the friction it
measures, a load as large as it) is refused, not subtracted, and flagged
``zero_under_load``; 0 is taken and the unknown zero's size enters the uncertainty. Where
the protocol ends with the load released at rest (``rest_after_sliding``), the rest after
the last movement is a second zero: the mean of the two is used (u from half their
difference, rectangular) and ``zero_drift`` is flagged when they differ by more than 3
combined standard errors and by more than ``settle_tol`` in μ. Nothing estimable: 0, with
``parameters.torque_offset_source`` saying so (``torque_offset_unknown``).

End stop. A stop at the end of the record — the sliding speed falling below
``stop_speed_fraction`` of the run's median speed and staying there to the end (a motor
ramping down, then at rest; the force falling with it) — is trimmed before the plateau is
searched (:func:`.intervals.end_stop`; speed over windows of 1 % of the record, so a
distance column's noise is no stop); ``parameters.instrument.end_stop_trimmed_mm`` says how much.

Contact. Samples with ``F_N`` below ``InstrumentConfig.contact_threshold_N`` are masked
(``in_contact`` False, ``mu`` NaN in the trace) and take no part in any statistic.

Detection of μ_S and μ_K (method ``"tribopipe-v2"``)
----------------------------------------------------
The order is fixed and has no circle: the plateau is found from the trace alone (step 3),
the static peak is the maximum *before* it (step 4), μ_K the mean *over* it (step 5). No
step uses a distance guessed for the pins: a stiff contact peaks after a few hundredths
of a millimetre, a soft pin of height h shears by about h·τ/G before it slides (6-mm
Ecoflex 00-50 at 11.8 kPa: 2–3 mm; Dragon Skin 30 at 106 kPa: ~1 mm), and a pre-sliding
may creep to the plateau with no peak at all.

1. Light median filter (``median_window`` samples) on μ removes spikes → ``mu_smooth``.
   Noise level σ: robust (MAD) standard deviation of the first differences of μ / √2.
2. The peak curve: a quadratic Savitzky–Golay smoothing of ``mu_smooth``
   (``peak_window_mm`` wide: it averages the noise and keeps a rounded peak) capped by the
   running maximum of a 3-sample moving average (so the polynomial cannot overshoot a
   peak that ends in a sudden slip). The window is short (0.015 mm ≈ 21 samples at
   0.007 mm/s and 10 Hz) because a static peak can be sharp: wider smoothing shaves it,
   narrower lets the noise lift it (bias ≤ ~0.015 at noise 0.015 on rounded peaks). A
   peak that ends in a sudden slip would still read low (the window reaches past the
   slip): where the quadratic fit of the ``cliff_window_mm`` before a sample exceeds the
   fit of the ``cliff_window_mm`` after it by more than ``cliff_sigma`` standard
   deviations (of the noise with its autocorrelation, :func:`.detection.effective_noise`: the fits
   average many samples), the sample is the top of a cliff and its value is the left fit's (when
   higher). A stiff contact's flank can be shorter than that window: near the start of
   sliding the left fit uses the samples there are (at least 7). The static peak is then
   re-read from as many samples as its shape allows (a short window reads the noise's
   maximum, not the peak's): a rounded peak by quadratics over windows that double in
   width around it (:func:`tribopipe.reduction.signals.quadratic_peak`), a peak ending in a
   sudden slip by quadratics over its flank that double in length backwards from the
   slip (:func:`tribopipe.reduction.signals.flank_peak`), each kept while the readings agree
   within ``peak_ici_gamma`` standard deviations and the fit matches the data within the
   noise (the intersection-of-confidence-intervals rule).
3. The plateau (the steady sliding of ASTM D1894) is where the trace has settled, searched
   from the run-in distance ``run_in_mm`` on (ASTM D2534) and nowhere else: the trace
   from there is cut in blocks of ``block_mm`` (of whole cycles where a stick-slip
   oscillation with at least 2× ``stick_slip_min_cycles`` cycles is found in the second
   half of that trace: blocks that cut cycles beat against them); the plateau starts at
   the first block from which every later block mean lies within a tolerance of their
   median (tolerance = the largest of ``settle_tol`` and z × the standard error of a
   block mean — from the per-sample noise with its autocorrelation counted
   (:func:`.detection.effective_noise`) — and z × the block-to-block scatter of the later half of
   the blocks: 1.4826·MAD of the second differences of the block means / √6, which
   stick-slip raises and a smooth transient — a peak, a run-in, a creep — does not; z
   is the normal quantile that keeps the chance
   of any of the blocks of a settled plateau falling outside at ``settle_alpha``). Where
   that noise allowance would exceed ``settle_tol``, the blocks are lengthened by the
   whole factor that brings it down (the scatter of a mean falls as 1/√length), up to
   half of ``plateau_min_mm``: a loose tolerance would let the tail of a transient into
   the plateau. A lengthened block averages what lies inside it (a soft pin's loading
   line rising through the plateau's level to its peak and falling back can average to
   that level), so the start is then refined inside the first block: it moves past the
   last of the test's own ``block_mm`` blocks there whose mean lies outside their
   tolerance. It ends at the end of the trace. A peak that stands out of the plateau
   cannot lie inside it, so the plateau needs no knowledge of the peak. When nothing
   settles, the last ``plateau_min_mm`` of the trace is used (and flagged).
4. μ_S is the static peak — the maximum transmittable friction force before gross
   sliding, the reading "at the instant the block slips" of ASTM D1894 and ISO 8295: the
   maximum of the peak curve from the start of sliding up to the plateau's start (and,
   only if ``static_search_mm`` is set, within that distance: a cap, off by default).
   A maximum at the edge of that range may lie beyond it (flagged; see
   ``peak_at_search_limit``).
5. μ_K is the mean of μ over the plateau. Drift test: least-squares slope of μ over s
   there [1/mm]; a slope larger than ``max_drift_per_mm`` and than 3 standard errors means
   the plateau is not steady.
6. μ_S is *distinct* when the peak stands above the plateau's own highs (its 99th
   percentile after the same smoothing) by more than ``static_min_prominence`` and
   ``static_prominence_sigma`` × the smoothed noise. Otherwise μ_S is reported equal to
   μ_K (the peak is not resolved), placed where the smoothed trace first reaches μ_K,
   and ``static_not_distinct`` is flagged; the raw peak is kept in
   ``parameters.mu_s_peak_raw``. So μ_S ≥ μ_K always.
7. Stick-slip: a periodic oscillation of the plateau. Its periodogram (after removing a
   quadratic trend, and divided by the power law fitted to it, so that a drifting
   zero's 1/f noise is locally flat) is searched for a line with at least
   ``stick_slip_min_cycles`` cycles in the window that stands above the local level of
   the neighbouring frequencies (:func:`tribopipe.reduction.signals.periodic_line`) by more than
   white or coloured
   noise would with probability ``stick_slip_false_alarm`` per run
   (:func:`tribopipe.reduction.signals.line_threshold`), and adds at least ``stick_slip_min_std``
   to μ's standard deviation. A test over the whole window sees a weak, regular
   oscillation that averaging over a second cannot separate from the noise (a
   0.01-peak-to-peak saw-tooth under noise 0.015 in a few millimetres of plateau).

Run-out is not stick-slip. A rotating disc that is not flat, or a pin off its track's
centre, adds an oscillation that repeats with every turn: a sinusoid at the rotation
frequency or its harmonics, not a saw-tooth. Where the plateau's line (step 7) has a
period within ``run_out_tolerance`` (plus the periodogram's own resolution, one period
over the window) of one revolution 2π·R or of its 2nd or 3rd harmonic, it is flagged
``run_out``, not ``stick_slip`` (:func:`.reduce.revolution_locked`; rotating instruments
only). Stick-slip keeps its own test; where a saw-tooth and run-out ride together the
strongest line names the flag.

Reciprocating runs (``"linear reciprocating"``, ASTM G133). The position is split into
strokes at its reversals (:func:`.reciprocating.split_strokes`: the position turns back by
more than a tenth of its range; a stroke shorter than half the range is not a full
stroke). Each stroke's μ is the mean friction force over its central
``stroke_core_fraction`` (away from the reversals, where the pin stops and turns) over
the mean F_N there, with the zero subtracted and signed against the motion. A cycle is a
forward and the following backward stroke; its μ is half the forward minus the backward
mean force over F_N, in which a zero offset and a tilt of the flat (a tangential load of
one sign both ways) cancel. The cycle series over the sliding path (each stroke adds its
length) goes through steps 1–7: μ_K is the mean over the settled plateau of cycles, with
its forward and backward averages (``parameters.mu_k_forward``, ``.mu_k_backward``)
and every cycle's μ (``parameters.cycles``). μ_S is the breakaway of the first stroke:
the maximum of the peak curve over its first half, distinct as in step 6 against that
stroke's own level and μ_K. The cycle means hold no zero, so μ_K's budget has no offset
term.

Flags (thresholds in :class:`~tribopipe.config.ReductionParams`)
----------------------------------------------
``static_not_distinct``  step 6 failed.
``peak_at_search_limit`` a distinct μ_S sits at the first sample of its search range
                         (within half a ``peak_window_mm``, the reading's resolution: the
                         trace may have started while sliding), or at its last when no
                         plateau settled (the peak may lie beyond); or the maximum sits at
                         a ``static_search_mm`` cap that ended the search before the
                         plateau, distinct or not. (A settled plateau holds no value as
                         high as a distinct peak: a peak right before it is inside.)
``no_steady_state``      no plateau of at least ``plateau_min_mm`` settles (step 3), or
                         the drift test fails (step 5).
``plateau_at_trace_end`` the μ_K window is bounded by the end of the trace rather than by
                         settled sliding: nothing settled (the window is the trace's last
                         ``plateau_min_mm``), or the settled plateau is shorter than
                         ``plateau_confirm_mm`` (twice the minimum plateau: the trace ends
                         before a second stretch could confirm the first).
``stick_slip``           the settled plateau oscillates (step 7).
``normal_force_unstable`` the coefficient of variation of F_N over the sliding contact
                         samples exceeds ``normal_force_cv_max``.
``short_trace``          the sliding distance is below ``run_in_mm + plateau_min_mm`` or
                         the plateau holds fewer than ``min_plateau_samples`` samples.
``torque_offset_unknown`` no set-up interval and no rest before motion: the torque zero
                         offset could not be estimated; 0 is assumed and the offset's
                         plausible size enters the uncertainty.
``zero_under_load``      the samples the zero would be read from already carry a
                         tangential load (above ``zero_load_max_fraction`` of the sliding
                         level): not subtracted; 0 is assumed and the unknown zero's size
                         enters the uncertainty.
``zero_drift``           the zero before sliding and the rest after it disagree.
``run_out``              the settled plateau oscillates with the disc's rotation (1×, 2×,
                         3×): run-out, not stick-slip.
``no_friction_signal``   the torque carries no friction: its samples while sliding are all
                         equal (a zero or stuck channel), or μ_K is within three standard
                         errors of zero (the plateau mean's, autocorrelation included).

Refused (one-line :class:`~tribopipe.errors.ReductionError`): time going backwards or
constant; a sliding distance that is not finite; a measured force, temperature, μ_K or μ_S
outside its range in :mod:`tribopipe.validate` (the column is not what its name and unit say).

References: ASTM D1894 (static and kinetic COF of plastic film: static = initial peak,
kinetic = average during uniform sliding); ISO 8295 (same principle for plastics film);
ASTM D2534 (kinetic COF of wax coatings: averaging after a run-in distance); ASTM G133
(linear reciprocating ball-on-flat sliding); ASTM G99 (pin-on-disk).
"""
