"""``python -m tumble_ros.analysis FILE.mcap [--figures DIR] [--json]`` (see cli.py)."""
import sys

from tumble_ros.exits import call_closing_quietly, end_if_stopped  # a closed pipe: 141, quietly

from .cli import main

sys.exit(end_if_stopped(call_closing_quietly(main, sys.argv)))
