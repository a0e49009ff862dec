"""``make demo``: the shipped synthetic campaign through the commands a user types.

Each command is printed as a user would type it and run through tribopipe's own command
line, all in this one Python process, so that numpy, pandas, pyarrow and matplotlib are
imported once rather than once per command (on a 2-core machine that is about a third of
the demo's time). The outputs are exactly those of the five commands run one by one.
"""

from __future__ import annotations

import shlex
import sys

from tribopipe.cli import main as tribopipe

OUT = "processed/demo"
# `batch` records its map in ./.tribopipe-map: the commands after it read that map without
# --map (and say so), as a user's next commands do
COMMANDS: tuple[tuple[str, ...], ...] = (
    ("batch", "configs/example.toml"),
    ("map", "table", "--format", "markdown", "-o", f"{OUT}/friction_map_groups.md"),
    ("export", "abaqus", "-o", f"{OUT}/friction.inp"),
    ("plot", "pairs"),
    ("report", "configs/example.toml"),
)


def run() -> int:
    """Run :data:`COMMANDS` in order; the exit code of the first that fails, else 0."""
    for args in COMMANDS:
        print(f"$ tribopipe {shlex.join(args)}", flush=True)
        try:
            tribopipe.main(list(args), prog_name="tribopipe")
        except SystemExit as exc:  # click ends every command with one
            if exc.code not in (0, None):
                return exc.code if isinstance(exc.code, int) else 1
    return 0


if __name__ == "__main__":
    sys.exit(run())
