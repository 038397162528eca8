"""Plain rclpy programs the ROS 2 tests run as separate processes: what a ROS 2 user would write, with no
simatch code in them."""
