"""The ROS 2 form of Foxglove's 3D-scene schemas (``foxglove_msgs/msg/SceneUpdate`` and what it contains).

Foxglove's 3D panel recognises a scene by its schema name; in a ROS 2 (CDR) recording that name is
``foxglove_msgs/msg/SceneUpdate``. The field lists below follow Foxglove's published schema reference
exactly (names, types and order decide the CDR layout); nothing else about them is ours. They live in a
type store of their own so that the simatch message store stays what ``simatch.msgs`` defines.
"""

from __future__ import annotations

from rosbags.typesys import Stores, get_types_from_msg, get_typestore

PACKAGE = "foxglove_msgs"

DEFINITIONS = {
    "Color": """
float64 r
float64 g
float64 b
float64 a
""",
    "KeyValuePair": """
string key
string value
""",
    "ArrowPrimitive": """
geometry_msgs/Pose pose
float64 shaft_length
float64 shaft_diameter
float64 head_length
float64 head_diameter
foxglove_msgs/Color color
""",
    "CubePrimitive": """
geometry_msgs/Pose pose
geometry_msgs/Vector3 size
foxglove_msgs/Color color
""",
    "SpherePrimitive": """
geometry_msgs/Pose pose
geometry_msgs/Vector3 size
foxglove_msgs/Color color
""",
    "CylinderPrimitive": """
geometry_msgs/Pose pose
geometry_msgs/Vector3 size
float64 bottom_scale
float64 top_scale
foxglove_msgs/Color color
""",
    "LinePrimitive": """
uint8 LINE_STRIP=0
uint8 LINE_LOOP=1
uint8 LINE_LIST=2
uint8 type
geometry_msgs/Pose pose
float64 thickness
bool scale_invariant
geometry_msgs/Point[] points
foxglove_msgs/Color color
foxglove_msgs/Color[] colors
uint32[] indices
""",
    "TriangleListPrimitive": """
geometry_msgs/Pose pose
geometry_msgs/Point[] points
foxglove_msgs/Color color
foxglove_msgs/Color[] colors
uint32[] indices
foxglove_msgs/KeyValuePair[] metadata
""",
    "TextPrimitive": """
geometry_msgs/Pose pose
bool billboard
float64 font_size
bool scale_invariant
foxglove_msgs/Color color
string text
""",
    "ModelPrimitive": """
geometry_msgs/Pose pose
geometry_msgs/Vector3 scale
foxglove_msgs/Color color
bool use_embedded_materials
string url
string mime_type
uint8[] data
""",
    "SceneEntityDeletion": """
uint8 MATCHING_ID=0
uint8 ALL=1
builtin_interfaces/Time timestamp
uint8 type
string id
""",
    "SceneEntity": """
builtin_interfaces/Time timestamp
string frame_id
string id
builtin_interfaces/Duration lifetime
bool frame_locked
foxglove_msgs/KeyValuePair[] metadata
foxglove_msgs/ArrowPrimitive[] arrows
foxglove_msgs/CubePrimitive[] cubes
foxglove_msgs/SpherePrimitive[] spheres
foxglove_msgs/CylinderPrimitive[] cylinders
foxglove_msgs/LinePrimitive[] lines
foxglove_msgs/TriangleListPrimitive[] triangles
foxglove_msgs/TextPrimitive[] texts
foxglove_msgs/ModelPrimitive[] models
""",
    "SceneUpdate": """
foxglove_msgs/SceneEntityDeletion[] deletions
foxglove_msgs/SceneEntity[] entities
""",
}

SCENE_UPDATE = f"{PACKAGE}/msg/SceneUpdate"

#: the standard ROS 2 types (geometry_msgs, builtin_interfaces) plus the Foxglove scene types
typestore = get_typestore(Stores.ROS2_JAZZY)
_types: dict = {}
for _name, _text in DEFINITIONS.items():
    _types.update(get_types_from_msg(_text, f"{PACKAGE}/msg/{_name}"))
typestore.register(_types)
