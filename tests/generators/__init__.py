"""Seeded synthetic exports with a known answer, for the tests and the benchmarks.

Not part of the product (the package in ``src/`` never imports them):

* :mod:`generators.synthetic`: the development family (shapes the detection was
  developed on) and the RheoCompass export writer (``write_intervals_export`` for any
  generator);
* :mod:`generators.contact`: the independent validation family, pins in series with a
  Dahl-type, elastic–plastic, slip-weakening contact, and its fixed grid;
* :mod:`generators.ratestate`: the third, unseen family, Dieterich–Ruina rate-and-state
  friction on the pins' spring (needs SciPy's ``solve_ivp``), and its fixed grid;
* :mod:`generators.instrument`: what an imperfect instrument does to a signal;
* :mod:`generators.truth`: the one known-answer type of the validation families.

``tests/`` is on the import path of pytest (``rootdir``-relative, as for the other helper
modules here); ``bench/`` and ``scripts/`` put it there themselves.
"""
