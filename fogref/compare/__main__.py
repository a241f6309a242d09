"""``python -m fogref.compare EXR --model NAME ...``: the ``fogref compare`` command alone."""

import sys

from fogref.compare import main
from fogref.errors import FogrefError

try:
    sys.exit(main())
except FogrefError as e:
    print(f"fogref compare: error: {e}", file=sys.stderr)
    sys.exit(2)
