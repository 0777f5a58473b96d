"""``python -m thermaxis.cli``: the ``thermaxis`` command without the console script."""

import sys

from thermaxis.cli import main

sys.exit(main())
