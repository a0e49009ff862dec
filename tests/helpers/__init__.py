"""Scaffolding shared by the tests: the published groups with a μ_S, campaign configs,
the ``reduce`` command as a user types it.

Fixtures live in ``conftest.py`` (``published_runs``, ``published_groups``); plain helpers
live here and are imported by name (``from helpers import with_mu_s``).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import pandas as pd
    from click.testing import Result

    from tribopipe.materials import Vocabulary

#: the ratio of μ_S to μ_K the simulator tests give the published groups (which hold no
#: μ_S): a breakaway above the kinetic value, as elastomers show
MU_S_RATIO = 1.4


def with_mu_s(groups: pd.DataFrame, factor: float = MU_S_RATIO) -> pd.DataFrame:
    """A copy of a group table with a μ_S column: ``factor`` × μ_K in every group, its 95 %
    interval ±0.02 around it, as many values as μ_K."""
    g = groups.copy()
    g["mu_s_n"] = g["mu_k_n"]
    g["mu_s_mean"] = g["mu_k_mean"] * factor
    g["mu_s_ci95_low"] = g["mu_s_mean"] - 0.02
    g["mu_s_ci95_high"] = g["mu_s_mean"] + 0.02
    return g


def write_campaign_config(root: Path, lines: list[str], extra: str = "",
                          names: dict[str, str] | None = None) -> Path:
    """``root/campaign.toml``: the ``[campaign]`` table's ``lines``, then ``extra`` (more
    tables), then a ``[names]`` table (short names of the file names → materials)."""
    table = names if names is not None else {"DS30": "Dragonskin 30"}
    body = "\n".join(["[campaign]", *lines]) + "\n" + extra + "\n[names]\n" + "".join(
        f'{short} = "{full}"\n' for short, full in table.items())
    cfg = root / "campaign.toml"
    cfg.write_text(body, encoding="utf-8")
    return cfg


def reduce_cli(*args: str | os.PathLike[str]) -> Result:
    """``tribopipe reduce ARGS`` in this process, as a user types it (exceptions kept in
    the result)."""
    from click.testing import CliRunner

    from tribopipe.cli import main

    return CliRunner().invoke(main, ["reduce", *(os.fsdecode(a) for a in args)])


def lab_vocabulary(*names: str) -> Vocabulary:
    """The shipped materials vocabulary with ``names`` added as a lab's own materials
    (class "other"): what a test whose made-up or hostile names must reach the map
    passes where names are resolved at the edge (``import_table(..., vocabulary=)``)."""
    from tribopipe.materials import Material, shipped_vocabulary

    return shipped_vocabulary().with_materials(
        Material(name=n, material_class="other") for n in names)
