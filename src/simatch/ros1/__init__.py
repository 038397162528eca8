"""ROS 1 interop: robot code written for the original Simatch (ROS 1, C++ or Python) plays in simatch
unchanged, and ROS users watch and record a run with their own tools (docs/ros.md).

* `bridge`: the bridge node, an adapter on the run's own nodes and messages (`rosside`: its rospy half);
* `embedded` (``simatch run ... --ros1``) and `client` (``simatch ros1 TEAM --connect ...``): where it joins;
* `convert` and `names`: the original's messages, units, names and topics;
* `rosenv`: Debian's ROS 1 from simatch's Python, and the message packages in ``share/`` (nubot_common,
  gazebo_msgs, and the example team simatch_demo);
* `bag`: a recording as a ROS 1 bag with the original's topics (``simatch export --format rosbag1``).

Only the modules that talk to a master import rospy (at run time): the rest works without ROS installed.
"""
