"""``python -m rosaos.cli``: the same as the ``rosaos`` console script."""

from rosaos.cli import main

main()
