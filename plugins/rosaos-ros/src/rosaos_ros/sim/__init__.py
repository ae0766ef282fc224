"""The rosbridge simulator: a simulated robot (TurtleBot 4, PuppyPi, any profile) behind a real
rosbridge v2 WebSocket server.

Run it alone with ``rosaos-ros-sim --profile turtlebot4 --port 9090`` and point any rosbridge
client at it (roslibpy, roslibjs, Foxglove's rosbridge connection); the driver's ``sim`` backend
starts one in a thread on a free port. Modules by role: :mod:`~rosaos_ros.sim.world` (physics),
:mod:`~rosaos_ros.sim.robot` (the profile's nodes, topics, services, actions),
:mod:`~rosaos_ros.sim.graph` (the ROS graph and ``/rosapi``), :mod:`~rosaos_ros.sim.server`
(the protocol), :mod:`~rosaos_ros.sim.simulator` (the whole, and its thread).
"""

from rosaos_ros.sim.simulator import Simulator, SimulatorError, SimulatorThread, sim_state

__all__ = ["Simulator", "SimulatorError", "SimulatorThread", "sim_state"]
