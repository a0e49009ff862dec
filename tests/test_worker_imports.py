"""Issue 10: a batch worker does not pay for SciPy's start-up (~0.9 s per process for
``scipy.signal``). The reduction's filters are NumPy
(:mod:`tribopipe.reduction.signals`); SciPy stays where it earns its import (``stats``'
Student-t quantiles, which a batch does not need).

Checked on a real ``tribopipe batch`` in a real process with a pool of two forked workers
and plots on: an audit hook logs every SciPy module imported and by which process, and a
fork hook logs whether SciPy was already loaded when a worker was forked (a worker
inherits its parent's modules). Loading SciPy afresh always shows in the log: its own
``import`` statements are audited even where the first module is reached by
``importlib``. The group statistics' Student-t quantile, run under the same hooks, shows
that the hook does see SciPy where it is imported.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from generators.synthetic import SyntheticRun, write_rheocompass_export

# Runs tribopipe's CLI after installing the hooks; every line of the log is
# "<pid> <event> <detail>".
WRAPPER = r"""
import os, runpy, sys

LOG = sys.argv[1]
PARENT = os.getpid()


def log(line):
    with open(LOG, "a", encoding="utf-8") as f:
        f.write(f"{os.getpid()} {line}\n")


def is_scipy(name):
    return name == "scipy" or name.startswith("scipy.")


def hook(event, args):
    if event == "import" and is_scipy(str(args[0])):
        log(f"import {args[0]}")


def forked():
    loaded = sorted(m for m in sys.modules if is_scipy(m))
    log(f"fork {'scipy-loaded' if loaded else 'clean'} parent={PARENT}")


sys.addaudithook(hook)
os.register_at_fork(after_in_child=forked)
log("parent")
sys.argv = ["tribopipe", *sys.argv[2:]]
runpy.run_module("tribopipe", run_name="__main__", alter_sys=True)
"""

# The same hooks around an import of SciPy: the check that the hook sees it.
CONTROL = WRAPPER.split("sys.argv = ", 1)[0] + "from scipy.special import stdtrit\n"


@pytest.fixture()
def campaign(tmp_path: Path) -> Path:
    """Four exports: an overshoot, a stick-slip run (the periodogram's path), a plain
    one and one cut short (a plateau at the trace's end); plots on."""
    raw = tmp_path / "raw"
    raw.mkdir()
    runs = {
        "DS30_steel_5N_20C_r1": SyntheticRun(normal_force_N=5.0, duration_s=400.0, seed=1),
        "DS30_steel_5N_20C_r2": SyntheticRun(normal_force_N=5.0, shape="stick_slip",
                                             duration_s=400.0, seed=2),
        "DS30_steel_1N_20C_r1": SyntheticRun(normal_force_N=1.0, mu_s=0.7, mu_k=0.6,
                                             duration_s=400.0, seed=3),
        "DS30_steel_1N_20C_r2": SyntheticRun(normal_force_N=1.0, peak_distance_mm=1.0,
                                             duration_s=238.0, seed=6),
    }
    for stem, run in runs.items():
        write_rheocompass_export(raw / f"{stem}.csv", run, project="p", test="t", sample="s")
    config = tmp_path / "campaign.toml"
    config.write_text(
        '[campaign]\nname = "imports"\nraw_dir = "raw"\noutput_dir = "out"\n'
        'filename_pattern = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"\nplots = true\n'
        '[names]\nDS30 = "Dragonskin 30"\n',
        encoding="utf-8",
    )
    return config


@pytest.mark.slow  # a real process or a larger data set: `pytest -m slow`
def test_batch_workers_reduce_and_plot_without_importing_scipy(campaign: Path,
                                                              tmp_path: Path) -> None:
    log = tmp_path / "imports.log"
    env = {**os.environ, "PYTHONIOENCODING": "utf-8"}
    done = subprocess.run(
        [sys.executable, "-c", WRAPPER, str(log), "batch", str(campaign), "--jobs", "2"],
        capture_output=True, text=True, env=env, timeout=300,
    )
    assert done.returncode == 0, done.stderr
    assert "4 reduced" in done.stdout and "0 failed" in done.stdout
    assert len(list((tmp_path / "out" / "plots" / "traces").glob("*.png"))) == 4

    lines = [line.split(" ", 2) for line in log.read_text(encoding="utf-8").splitlines()]
    parent = next(pid for pid, event, *_ in lines if event == "parent")
    forks = [(pid, rest[0]) for pid, event, *rest in lines if event == "fork"]
    workers = {pid for pid, _ in forks if pid != parent}
    assert len(workers) >= 2, forks  # the pool really forked its two workers
    assert all(detail.startswith("clean") for _, detail in forks), forks
    imports = [(pid, rest[0]) for pid, event, *rest in lines if event == "import"]
    assert [i for i in imports if i[0] in workers] == []
    # the hook does see SciPy where it is imported (scipy.special), through the same
    # hooks
    control = tmp_path / "control.log"
    asked = subprocess.run(
        [sys.executable, "-c", CONTROL, str(control)],
        capture_output=True, text=True, env=env, timeout=300,
    )
    assert asked.returncode == 0, asked.stderr
    seen = {line.split(" ")[-1] for line in control.read_text(encoding="utf-8").splitlines()
            if " import " in line}
    assert "scipy" in seen and any(name.startswith("scipy.special") for name in seen)
