"""``python -m rosaos_ros.sim``: the same as ``rosaos-ros-sim``."""

from rosaos_ros.sim.cli import main

raise SystemExit(main())
