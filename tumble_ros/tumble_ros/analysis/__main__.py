"""``python -m tumble_ros.analysis FILE.mcap [--figures DIR] [--json]`` (see cli.py)."""
import sys

from .cli import main

sys.exit(main())
