"""Publish, validate and merge at 10³–10⁵ rows: peak memory, wall and CPU of each command.

Each command runs as its own process through the real CLI (``python -m tribopipe``) under
``/usr/bin/time -v``, which reports the process's peak resident set size (``Maximum
resident set size``), its wall time and its CPU time (user + system). The maps are built
through the package's own API from ``bench_scale``'s copies of one real reduced run, in
three shapes:

* ``grid``: the founding grid's 18 pairs and 180 condition groups (more runs are more
  repeats: a group holds N/180 runs);
* ``one group``: every run in one condition group (a group of N runs);
* ``own pins``: each 1,000 runs under a pin name of their own, as ``bench_explorer`` builds
  them (pairs and groups grow with the runs: 18,000 groups at 10⁵ rows; the explorer must
  still stay a page).

For each map: ``map validate`` of the map folder itself (every check there is: each
part's bytes and rows against their checksums, every row, the stored groups against the
rows), ``map publish`` (no evidence: the runs are copies of one run), ``map validate`` of
the package, ``map merge`` of the package into an empty map, and the sizes
of the package's ``explorer.html`` and of the files beside it. Run from the repository::

    PYTHONPATH=src:tests:bench python bench/bench_publish.py [--sizes 1000 10000 100000]
        [--shapes grid "one group" "own pins"]

Prints one line per map and command and writes ``bench/publish.json`` (with the load
average before and after each command: the machine is shared).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import bench_scale

HERE = Path(__file__).parent
ROOT = HERE.parent
SHAPES = ("grid", "one group", "own pins")


#: ``bench_scale``'s grid names that the shipped vocabulary does not resolve to one
#: material by itself (a lab would have named it so on the way in)
CANONICAL = {"aluminium lathed": "lathed aluminium disk"}


def canonical(name: str) -> str:
    """The shipped vocabulary's canonical name of a grid name of ``bench_scale`` (the
    names a reduction resolves on the way in; ``map merge`` refuses others)."""
    from tribopipe.materials import shipped_vocabulary

    found = shipped_vocabulary().candidates(CANONICAL.get(name, name))
    return found[0] if len(found) == 1 else name


def build(folder: Path, n: int, shape: str, template: dict) -> Path:
    """A map of ``n`` rows of ``shape`` (see the module docstring), landed 20,000 rows at
    a time, its pin and disc names the vocabulary's canonical ones."""
    from tribopipe.frictionmap import update_map

    path = folder / f"{shape.replace(' ', '_')}_{n}.parquet"
    for k in range(0, n, 20_000):
        records = bench_scale.records(template, min(20_000, n - k), k)
        for j, r in enumerate(records):
            i = k + j
            r["pin"], r["disc"] = canonical(r["pin"]), canonical(r["disc"])
            if shape == "one group":
                r["pin"], r["disc"] = "Dragonskin 30", "steel"
                r["normal_force_N"], r["pressure_kPa"] = 3.0, 11.789 * 3.0
                r["temperature_C"], r["repeat"] = 20.0, i + 1
            elif shape == "own pins":
                r["pin"] = f"{r['pin']} lot {i // 1000}"
        update_map(path, records)
    return path


def timed(args: list[str], env: dict[str, str]) -> dict:
    """Run ``python -m tribopipe ARGS`` under ``/usr/bin/time -v``: exit code, wall [s],
    CPU [s] (user + system), peak RSS [MB], the load average before and after."""
    load_before = os.getloadavg()[0]
    cmd = ["/usr/bin/time", "-v", sys.executable, "-m", "tribopipe", *args]
    done = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
    err = done.stderr

    def field(name: str) -> str:
        match = re.search(rf"^\s*{re.escape(name)}: (.+)$", err, re.MULTILINE)
        return match.group(1).strip() if match else "nan"

    wall_text = field("Elapsed (wall clock) time (h:mm:ss or m:ss)")
    parts = [float(x) for x in wall_text.split(":")] if wall_text != "nan" else [float("nan")]
    wall = sum(v * 60 ** k for k, v in enumerate(reversed(parts)))
    row = {
        "exit": done.returncode,
        "wall_s": round(wall, 2),
        "cpu_s": round(float(field("User time (seconds)")) + float(field("System time (seconds)")),
                       2),
        "peak_MB": round(float(field("Maximum resident set size (kbytes)")) / 1024, 1),
        "load": [round(load_before, 1), round(os.getloadavg()[0], 1)],
    }
    if done.returncode:
        row["output"] = (done.stdout + err).strip().splitlines()[:3]
    return row


def measure(path: Path, folder: Path, env: dict[str, str]) -> list[dict]:
    """``map validate`` of the map, ``map publish``, ``map validate`` and ``map merge`` of
    its package, and the page sizes."""
    package = folder / (path.stem + "_pkg")
    target = folder / (path.stem + "_merged.parquet")
    out = []
    steps = [
        ("validate map", ["map", "validate", str(path)]),
        ("publish", ["map", "publish", "--map", str(path), "-o", str(package), "--lab",
                     "Bench Lab", "--no-evidence", "--overwrite"]),
        ("validate", ["map", "validate", str(package)]),
        ("merge", ["map", "merge", str(package), "--map", str(target)]),
    ]
    for name, args in steps:
        row = {"command": name, **timed(args, env)}
        if name == "publish" and not row["exit"]:
            page = package / "explorer.html"
            beside = [p for p in package.rglob("*") if p.is_file()
                      and p.relative_to(package).parts[0].startswith("explorer_")]
            pages = [p for p in beside if p.suffix == ".html"]
            row["largest_page_MB"] = round(max([page.stat().st_size]
                                               + [p.stat().st_size for p in pages]) / 1e6, 2)
            row["page_MB"] = round(page.stat().st_size / 1e6, 2)
            row["beside_MB"] = round(sum(p.stat().st_size for p in beside) / 1e6, 2)
            row["beside_files"] = len(beside)
            row["largest_beside_MB"] = round(max((p.stat().st_size for p in beside),
                                                 default=0) / 1e6, 3)
            row["package_MB"] = round(sum(p.stat().st_size for p in package.rglob("*")
                                          if p.is_file()) / 1e6, 1)
        out.append(row)
    shutil.rmtree(package, ignore_errors=True)
    shutil.rmtree(target, ignore_errors=True)
    return out


def main(argv: list[str] | None = None) -> list[dict]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1000, 10_000, 100_000])
    parser.add_argument("--shapes", nargs="+", default=list(SHAPES), choices=SHAPES)
    parser.add_argument("--keep", type=Path, help="build the maps here and keep them")
    parser.add_argument("--output", type=Path, default=HERE / "publish.json")
    args = parser.parse_args(argv)
    folder = args.keep or Path(tempfile.mkdtemp(prefix="bench_publish_"))
    folder.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), env.get("PYTHONPATH", "")])
    rows = []
    try:
        template = bench_scale.template_record(folder)
        for shape in args.shapes:
            for n in args.sizes:
                path = folder / f"{shape.replace(' ', '_')}_{n}.parquet"
                if not path.exists():
                    path = build(folder, n, shape, template)
                for row in measure(path, folder, env):
                    row = {"shape": shape, "rows": n, **row}
                    print(json.dumps(row, ensure_ascii=False), flush=True)
                    rows.append(row)
    finally:
        if args.keep is None:
            shutil.rmtree(folder, ignore_errors=True)
    result = {"measured": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
              "cpus": os.cpu_count(), "rows": rows}
    args.output.write_text(json.dumps(result, indent=1, ensure_ascii=False) + "\n",
                           encoding="utf-8")
    return rows


if __name__ == "__main__":
    main()
