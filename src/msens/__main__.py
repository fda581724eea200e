"""``python -m msens``: the ``msens`` command (:func:`msens.cli.main`)."""

import sys

from msens.cli import main

if __name__ == "__main__":
    sys.exit(main())
