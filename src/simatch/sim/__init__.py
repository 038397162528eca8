"""The simulation subsystem: the MuJoCo world, robots, ball handling, perception and the Gazebo-like interface."""
