"""``python -m convexguid.robustness``: see :mod:`convexguid.robustness.bench`."""

import sys

from convexguid.robustness.bench import main

sys.exit(main())
