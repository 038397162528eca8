#!/usr/bin/env bash
# System packages the test suite needs that pip cannot provide, all from Debian's apt:
# - Chromium, which the browser tests drive through Playwright (a browser download by Playwright is
#   impossible on the target machines);
# - ROS 1 (roscore, rospy, rostopic, rosmsg, rosbag, the standard messages and genpy), which the ROS tests
#   run for real against simatch's bridge (docs/ros.md);
# - cmake and a C++ compiler, with which the ros2 extra's rosidl tools build simatch_msgs for ROS 2.
set -euo pipefail
ROS1_PACKAGES=(ros-core python3-rospy python3-rostopic python3-rosbag python3-rosmsg python3-roslaunch rosbash
    ros-std-msgs python3-std-msgs libstd-msgs-dev ros-geometry-msgs python3-geometry-msgs libgeometry-msgs-dev
    ros-rosgraph-msgs python3-rosgraph-msgs python3-genpy python3-message-filters)

missing=()
command -v chromium >/dev/null 2>&1 || missing+=(chromium)
command -v cmake >/dev/null 2>&1 || missing+=(cmake)
command -v c++ >/dev/null 2>&1 || missing+=(g++)
if ! { command -v roscore && command -v rostopic && command -v rosbag && command -v rosmsg \
        && [ -f /usr/share/std_msgs/package.xml ] && [ -f /usr/share/geometry_msgs/package.xml ] \
        && /usr/bin/python3 -c "import rospy, genpy, message_filters" ; } >/dev/null 2>&1; then
    missing+=("${ROS1_PACKAGES[@]}")
fi
if [ "${#missing[@]}" -eq 0 ]; then
    exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
        echo "install-system-deps: this user cannot run apt-get; install Debian's packages: ${missing[*]}" >&2
        exit 1
    fi
fi
export DEBIAN_FRONTEND=noninteractive
# other jobs on a shared machine may hold apt's lock for a while: wait for it rather than fail
APT=(-o DPkg::Lock::Timeout=600)
$SUDO apt-get "${APT[@]}" update -qq
$SUDO apt-get "${APT[@]}" install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
command -v chromium >/dev/null
command -v roscore >/dev/null
command -v cmake >/dev/null
command -v c++ >/dev/null
