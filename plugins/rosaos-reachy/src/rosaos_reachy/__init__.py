"""rosaOS driver for the Pollen Robotics Reachy Mini (see ``rosaos_reachy.plugin``)."""
