"""`python -m dqjulia ...`: the same as the `dqjulia` command."""

import sys

from ._cli import main

sys.exit(main())
