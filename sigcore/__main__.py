"""``python -m sigcore`` = the ``sigcore`` command."""

from .cli import main

main()
