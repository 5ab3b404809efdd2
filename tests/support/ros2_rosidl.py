"""Compute RIHS01 type hashes with ROS 2's own rosidl tools, and write them down.

Run once, in a venv with ROS 2 Kilted's wheels (not a test dependency: ~280 MB, ~80 s):

    python -m venv /tmp/ros2venv && /tmp/ros2venv/bin/pip install ros-rclpy \\
        ros-rmw-fastrtps-cpp ros-rosidl-generator-type-description ros-rosidl-adapter \\
        ros-std-msgs ros-rosgraph-msgs ros-geometry-msgs ros-sensor-msgs ros-service-msgs
    /tmp/ros2venv/bin/python tests/support/ros2_rosidl.py SIMULATION_INTERFACES_CHECKOUT \\
        /tmp/ros2venv/share > tests/support/ros2_rosidl_hashes.json

SIMULATION_INTERFACES_CHECKOUT is ros-simulation/simulation_interfaces at 2.1.0 (its msg/,
srv/ and action/ folders). Each file goes through rosidl_adapter (.msg/.srv/.action to
.idl) and rosidl_generator_type_description (the type description and its hash), with the
wheels' share/<package>/**/*.json as the descriptions of the packages it includes; tf2_msgs
(no wheel) is made from its one-line TFMessage.msg the same way.
"""

from __future__ import annotations

import contextlib
import json
import sys
import tempfile
from pathlib import Path

TF_MESSAGE = "geometry_msgs/TransformStamped[] transforms\n"
STANDARD = ("rosgraph_msgs/msg/Clock", "sensor_msgs/msg/JointState", "std_msgs/msg/String",
            "action_msgs/srv/CancelGoal", "action_msgs/msg/GoalStatusArray")


def package_hashes(package_dir: Path, share: Path) -> dict[str, str]:
    from rosidl_adapter import convert_to_idl
    from rosidl_generator_type_description import generate_type_hash

    out = Path(tempfile.mkdtemp())
    idl_dir, tuples = out / "idl", []
    for path in sorted(package_dir.glob("*/*")):
        if path.suffix in (".msg", ".srv", ".action"):
            with contextlib.redirect_stdout(sys.stderr):  # it prints what it reads
                idl = convert_to_idl(package_dir, package_dir.name,
                                     path.relative_to(package_dir), idl_dir)
            tuples.append(f"{idl_dir}:{idl.relative_to(idl_dir)}")
    includes = [f"{p.name}:{p}" for p in share.iterdir() if p.is_dir()]
    args = {"package_name": package_dir.name, "output_dir": str(out / "json"),
            "idl_tuples": tuples, "include_paths": includes}
    (out / "args.json").write_text(json.dumps(args))
    hashes = {}
    for path in generate_type_hash(str(out / "args.json")):
        top = json.loads(path.read_text())["type_hashes"][0]
        hashes[top["type_name"]] = top["hash_string"]
    return hashes


def main(checkout: Path, share: Path) -> None:
    hashes = package_hashes(checkout, share)
    tf_dir = Path(tempfile.mkdtemp()) / "tf2_msgs"
    (tf_dir / "msg").mkdir(parents=True)
    (tf_dir / "msg" / "TFMessage.msg").write_text(TF_MESSAGE)
    hashes.update(package_hashes(tf_dir, share))
    for name in STANDARD:
        package, kind, message = name.split("/")
        described = json.loads((share / package / kind / f"{message}.json").read_text())
        hashes[name] = described["type_hashes"][0]["hash_string"]
    json.dump(hashes, sys.stdout, indent=1, sort_keys=True)
    print()


if __name__ == "__main__":
    main(Path(sys.argv[1]), Path(sys.argv[2]))
