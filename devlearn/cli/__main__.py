"""Allow ``python -m devlearn.cli``."""

import sys

from devlearn.cli import main

sys.exit(main())
