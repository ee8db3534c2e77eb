"""``python -m comove_dolfinx ...``: the ``comove`` command (cli.py) under the interpreter at hand."""
import sys

from .cli import main

sys.exit(main())
