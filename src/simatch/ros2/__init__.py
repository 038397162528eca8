"""simatch on the ROS 2 graph: the bridge (``simatch ros2``), simatch's messages as ROS 2 interface packages,
and what a recording needs to be a rosbag2 folder. See docs/ros.md ("ROS 2").

Nothing here imports ``rclpy`` at import time: the bridge runs it in a process of its own (`simatch.ros2.node`),
so ROS 2's executor and DDS threads never run in a simulation's process.
"""
