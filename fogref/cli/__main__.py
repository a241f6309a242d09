"""``python -m fogref.cli ...``: the same as the ``fogref`` script."""

import sys

from fogref.cli import main

sys.exit(main())
