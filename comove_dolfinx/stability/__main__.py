"""python -m comove_dolfinx.stability: see the package docstring."""
from . import main

raise SystemExit(main())
