"""``python -m correlations.cli``: the ``vesicle-tube`` command."""

import sys

from correlations.cli import main

sys.exit(main())
