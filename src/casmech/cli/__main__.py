"""`python -m casmech.cli`: the command line."""

import sys

from casmech.cli import main

sys.exit(main())
