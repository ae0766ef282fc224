"""rosaOS driver for ROS 2 robots over rosbridge, with its rosbridge simulator (:mod:`rosaos_ros.sim`).

The driver's declaration is :mod:`rosaos_ros.plugin`; how the parts fit is in :mod:`rosaos_ros.backend`.
"""
