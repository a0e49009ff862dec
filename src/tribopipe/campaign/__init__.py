"""A campaign: a table of raw exports with their metadata, reduced incrementally in parallel.

A campaign is described by a TOML file (``configs/*.toml``)::

    [campaign]
    name = "example"
    raw_dir = "../raw/example"           # paths are relative to the config file's folder
    glob = "*.csv"                       # default: every export the readers know (.csv,
                                         # .txt, .tsv, .xlsx, .xls, any case); never the
                                         # manifest, configs or the tool's own outputs
    instrument = "instruments/t-pid44.toml"     # default: the founding T-PID/44 cell
    output_dir = "../processed"          # default: processed/ beside the config's folder
    map = "../processed/friction_map.parquet"   # default: <output_dir>/friction_map.parquet
    manifest = "../raw/example/manifest.csv"   # optional column `test`: one row per test
    filename_pattern = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"
    test_pattern = "{pin} on {disc}, {force} N, {temperature} °C, #{repeat}"  # each Test name
    # use_export_names = true + export_pattern = "...": the older spelling of test_pattern
    force_tolerance_N = 0.0              # QC: measured F_N may stray max(tol_N, tol_rel·F_nom)
    force_tolerance_rel = 0.10
    temperature_tolerance_C = 2.0        # QC: measured T may stray this far from nominal
    speed_tolerance_rel = 0.10           # QC: measured sliding speed vs nominal (fraction)
    plots = true                         # per-run trace plots under <output_dir>/plots/traces
    encoding = "utf-16"                  # optional: force the reader's encoding, delimiter
    delimiter = "tab"                    # ("tab", ";", ",") or decimal mark (".", ","),
    decimal = ","                        # else they are detected per file

    [reduction]                          # optional: overrides the instrument config's table
    median_window = 5

    [names]                              # optional: short names in file names -> full names
    DS30 = "Dragonskin 30"

The package's rooms, each importing only those above it:

* :mod:`~tribopipe.campaign.patterns` — the label fields and the file-name patterns;
* :mod:`~tribopipe.campaign.spec` — :class:`Campaign`, :func:`load_campaign`,
  :func:`folder_campaign`;
* :mod:`~tribopipe.campaign.metadata` — the manifest (a row per file, or per test of a
  session export), the merge of metadata sources per test (which must agree; a test whose
  metadata is missing or contradictory fails alone);
* :mod:`~tribopipe.campaign.state` — the incremental state, typed (:class:`CampaignState`:
  each file and its runs as the last batch found them), read and written in one place;
* :mod:`~tribopipe.campaign.table` — which files are exports (:func:`discover_files`) and
  the campaign as a table (:func:`campaign_table`, one row per file, its content hash
  trusted while size and ``mtime_ns`` are unchanged; :func:`campaign_listing`, one per
  run);
* :mod:`~tribopipe.campaign.outputs` — ``runs.csv`` (one row per run) and ``failures.csv``;
* :mod:`~tribopipe.campaign.worker` — one file in a worker: read once, every run labelled
  and reduced;
* :mod:`~tribopipe.campaign.ledger` — a batch's account and its ledger
  (:class:`BatchReport`), whose parts add up;
* :mod:`~tribopipe.campaign.batch` — :func:`run_campaign`, the parallel batch, the same
  content under two names (duplicate or conflict), landed as it goes through the one
  landing (:func:`tribopipe.pipeline.landing.land_runs`).

Every friction interval of every test of every export is a run. A file whose content,
labels or config changed is reduced again and its old map rows replaced; a failed file is
retried once it changes. The package exports a campaign's everyday calls
(:data:`__all__`); every other name is imported from the room that defines it.
"""

from __future__ import annotations

from .batch import run_campaign
from .ledger import BatchReport
from .metadata import read_manifest
from .spec import Campaign, folder_campaign, load_campaign
from .table import campaign_listing, campaign_table, manifest_template

__all__ = [
    "Campaign",
    "load_campaign",
    "folder_campaign",
    "read_manifest",
    "campaign_table",
    "campaign_listing",
    "manifest_template",
    "run_campaign",
    "BatchReport",
]
