"""``python -m tribopipe`` is the same as the ``tribopipe`` command."""

from tribopipe.cli import main

main()
