"""rosaOS driver for Pollen Robotics Reachy Mini (placeholder; see ``rosaos_reachy.plugin``)."""
