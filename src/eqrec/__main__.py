"""``python -m eqrec``: the command-line interface (same as the ``eqrec`` command)."""

from eqrec.cli import main

raise SystemExit(main())
