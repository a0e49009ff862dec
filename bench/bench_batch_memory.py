"""The batch's parent memory per file, by ``tracemalloc``: what it keeps of a campaign
before any work (the state's entries decoded, the campaign table, the plan).

Over a campaign a batch already ran (e.g. ``bench_rerun.py``'s ``n10000`` folder): the
state is read, the table built and the plan made as ``tribopipe batch`` does, and the
bytes each keeps after a garbage collection are divided by the number of files. Read-only
(the state is opened read-only, no export is read: their size and ``mtime_ns`` match).

    nice python bench/bench_batch_memory.py bench/out/rerun/n10000/campaign.toml
"""

from __future__ import annotations

import argparse
import gc
import json
import time
import tracemalloc
from pathlib import Path


def main(argv: list[str] | None = None) -> dict[str, float]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("config", type=Path)
    args = parser.parse_args(argv)
    from tribopipe.campaign import batch, state, table
    from tribopipe.campaign.spec import load_campaign

    campaign = load_campaign(args.config)
    gc.collect()
    tracemalloc.start()
    cpu = time.process_time()
    kept = state.load_state(campaign)
    gc.collect()
    after_state = tracemalloc.get_traced_memory()[0]
    rows = table.campaign_table(campaign, state=kept)
    gc.collect()
    after_table = tracemalloc.get_traced_memory()[0]
    plan = batch._plan(rows, set())
    gc.collect()
    after_plan, peak = tracemalloc.get_traced_memory()
    n = max(1, len(rows))
    result = {"files": len(rows), "state_B_per_file": after_state / n,
              "table_B_per_file": (after_table - after_state) / n,
              "plan_B_per_file": (after_plan - after_table) / n,
              "total_B_per_file": after_plan / n, "peak_B_per_file": peak / n,
              "cpu_s": time.process_time() - cpu}
    del plan
    print(json.dumps({k: round(v) if k != "cpu_s" else round(v, 2)
                      for k, v in result.items()}))
    return result


if __name__ == "__main__":
    main()
