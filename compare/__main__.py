"""``python -m mechcheck``: the same command line as the ``mechcheck`` script."""

from mechcheck.cli import main

main()
