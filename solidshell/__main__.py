"""``python -m solidshell ...`` -- the same as the ``solidshell`` command."""

import sys

from .cli import main

sys.exit(main())
