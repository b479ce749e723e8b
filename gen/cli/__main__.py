"""``python -m npstereo.gen.cli``: the ``npstereo`` command."""

import sys

from .main import main

sys.exit(main())
