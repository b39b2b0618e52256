"""``python -m cobra_ref`` = the ``cobra-ref`` command."""

from .cli import main

raise SystemExit(main())
