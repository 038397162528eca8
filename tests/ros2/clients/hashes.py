"""Print, as JSON, the RIHS01 type hash rclpy announces for each message type named on the command line, and
the CDR rclpy makes of a VelCmd(stamp=1.5, tick=3, vx=1, vy=-0.5, w=0.25) (a plain rclpy program)."""

import importlib
import json
import sys

import rclpy
from rclpy.serialization import serialize_message


def main() -> None:
    rclpy.init()
    node = rclpy.create_node("hashes_test")
    out = {}
    for k, name in enumerate(sys.argv[1:]):
        pkg, _, typ = name.split("/")
        cls = getattr(importlib.import_module(f"{pkg}.msg"), typ)
        topic = f"/hash_test_{k}"
        node.create_publisher(cls, topic, 1)
        out[name] = str(node.get_publishers_info_by_topic(topic)[0].topic_type_hash)
    from simatch_msgs.msg import VelCmd

    out["velcmd_cdr"] = serialize_message(VelCmd(stamp=1.5, tick=3, vx=1.0, vy=-0.5, w=0.25)).hex()
    print(json.dumps(out))
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
