"""
Command-line tools and build tooling over the core: what a terminal user runs.

``python -m tumble_ros.cli.ensemble`` (ensembles, progress on stderr), ``python -m
tumble_ros.cli.warmup`` (compile the integration loops ahead, as ``make setup`` does), and the
progress display both use. The core stays a library: it imports nothing from here.
"""
