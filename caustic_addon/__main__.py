"""`python -m caustic_addon`: the command line in cli.py."""

import sys

from .cli.main import main

sys.exit(main())
