"""``python -m convexguid.classics``: see :mod:`convexguid.classics.bench`."""

import sys

from convexguid.classics.bench import main

sys.exit(main())
