"""`python -m caustic_addon`: the command line in cli.py."""

import sys

from .cli import main

sys.exit(main())
