"""The ROS 2 front's wire format against fixed references: RIHS01 hashes against the
values rosidl computed (tests/support/ros2_rosidl_hashes.json, made by
tests/support/ros2_rosidl.py), and
keys, liveliness tokens and attachments against rmw_zenoh's docs/design.md examples."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore
from typer.testing import CliRunner

from galton.daemon.cli import app as daemon_app
from galton.daemon.fronts.ros2 import interfaces, rmw_zenoh
from galton.daemon.fronts.ros2.messages import decode, encode, header, new, tf_cdr, vector
from galton.protocol import InvalidArgumentError

ROSIDL = json.loads((Path(__file__).parents[2] / "support" / "ros2_rosidl_hashes.json").read_text())
# From rmw_zenoh docs/design.md.
STRING_HASH = "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"
ADD_TWO_INTS_HASH = "RIHS01_e118de6bf5eeb66a2491b5bda11202e7b68f198d6f67922cf30364858239c81a"
ADD_TWO_INTS = "example_interfaces::srv::dds_::AddTwoInts_"
# rclpy 9.1.2 (Kilted wheels), as printed by
#   serialize_message(Clock(clock=Time(sec=3, nanosec=5))).hex()
#   serialize_message(JointState(name=["a", "bc"], position=[0.5, -1.0])).hex()
# Fast-CDR leaves alignment padding uninitialised (bytes 17-19 here, after frame_id's NUL)
# and rclpy returned 8 bytes past the message's end: those are not the message's.
RCLPY_CLOCK = bytes.fromhex("000100000300000005000000")
RCLPY_JOINT_STATE = bytes.fromhex(
    "00010000000000000000000001000000003b3199020000000200000061000000030000006263000002000000"
    "000000000000e03f000000000000f0bf00000000000000001c2ca851d11c2fd4")
JOINT_STATE_PADDING = {17, 18, 19}


def checked_types() -> list[str]:
    """Every type rosidl hashed (the action type itself is in no key: its services and
    feedback message are)."""
    return sorted(name for name in ROSIDL if name != interfaces.ACTION)


def test_every_hash_equals_rosidls() -> None:
    mine = {name: interfaces.type_hash(name) for name in checked_types()}
    assert mine == {name: ROSIDL[name] for name in checked_types()}
    assert len(mine) >= 120  # 22 services x 4 types, 15 messages, the action's, standard


def test_service_hashes_are_the_service_types_not_the_requests() -> None:
    step = interfaces.service_type("StepSimulation")
    assert interfaces.type_hash(step) != interfaces.type_hash(f"{step}_Request")
    assert interfaces.dds_type_name(step) == "simulation_interfaces::srv::dds_::StepSimulation_"


def test_design_document_hashes() -> None:
    """The document's String and AddTwoInts hashes, by the front's construction of a
    service (which needs ServiceEventInfo's char GID read as uint8, as rosidl does)."""
    store = interfaces.typestore()
    assert store.hash_rihs01("std_msgs/msg/String") == STRING_HASH
    fresh = get_typestore(Stores.ROS2_KILTED)
    interfaces._gid_as_uint8(fresh)
    saved, interfaces.PACKAGE = interfaces.PACKAGE, "example_interfaces"
    try:
        fresh.register(interfaces._service_types("AddTwoInts", "int64 a\nint64 b",
                                                 "int64 sum"))
    finally:
        interfaces.PACKAGE = saved
    assert fresh.hash_rihs01("example_interfaces/srv/AddTwoInts") == ADD_TWO_INTS_HASH


def test_key_expressions_are_the_design_documents() -> None:
    chatter = ("std_msgs::msg::dds_::String_", STRING_HASH)
    assert rmw_zenoh.key_expr(0, rmw_zenoh.qualified_name("", "chatter"), *chatter) == (
        f"0/chatter/std_msgs::msg::dds_::String_/{STRING_HASH}")
    assert rmw_zenoh.key_expr(0, rmw_zenoh.qualified_name("/robot1", "chatter"),
                              *chatter) == f"0/robot1/chatter/{chatter[0]}/{STRING_HASH}"
    assert rmw_zenoh.key_expr(2, "/add_two_ints", ADD_TWO_INTS, ADD_TWO_INTS_HASH) == (
        f"2/add_two_ints/{ADD_TWO_INTS}/{ADD_TWO_INTS_HASH}")


def test_liveliness_tokens_are_the_design_documents() -> None:
    listener = rmw_zenoh.NodeIdentity(2, "aac3178e146ba6f1fc6e6a4085e77f21", 0, "",
                                      "listener")
    assert listener.node_token() == (
        "@ros2_lv/2/aac3178e146ba6f1fc6e6a4085e77f21/0/0/NN/%/%/listener")
    server = rmw_zenoh.NodeIdentity(2, "f9980ee0495eaafb3e38f0d19e2eae12", 0, "",
                                    "add_two_ints_server")
    assert server.entity_token(10, rmw_zenoh.SERVICE_SERVER, "/add_two_ints", ADD_TWO_INTS,
                               ADD_TWO_INTS_HASH, rmw_zenoh.SERVICE_QOS) == (
        "@ros2_lv/2/f9980ee0495eaafb3e38f0d19e2eae12/0/10/SS/%/%/add_two_ints_server/"
        f"%add_two_ints/{ADD_TWO_INTS}/{ADD_TWO_INTS_HASH}/::,10:,:,:,,")
    sim = rmw_zenoh.NodeIdentity(0, "ab", 0, "/sim/robot1", "galton")
    assert sim.node_token().endswith("/NN/%/%sim%robot1/galton")


def test_attachment_layout() -> None:
    gid = bytes(range(16))
    data = rmw_zenoh.Attachment(7, 1_700_000_000_000_000_000, gid).encode()
    assert data == ((7).to_bytes(8, "little") + (1_700_000_000_000_000_000).to_bytes(8, "little")
                    + b"\x10" + gid)
    reply = rmw_zenoh.Attachment.decode(data).reply()
    assert (reply.sequence, reply.gid) == (7, gid)
    assert len(reply.encode()) == rmw_zenoh.ATTACHMENT_LENGTH == 33
    with pytest.raises(InvalidArgumentError, match="33 bytes"):
        rmw_zenoh.Attachment.decode(data[:-1])


def test_namespaces_are_checked() -> None:
    assert rmw_zenoh.check_namespace("sim/") == "/sim"
    with pytest.raises(InvalidArgumentError, match="not a ROS namespace"):
        rmw_zenoh.check_namespace("/1sim")


def test_cdr_equals_rclpys_bytes() -> None:
    clock = new(interfaces.CLOCK, clock=new("builtin_interfaces/msg/Time", sec=3, nanosec=5))
    assert encode(clock, interfaces.CLOCK) == RCLPY_CLOCK
    state = new(interfaces.JOINT_STATE, name=["a", "bc"],
                position=np.array([0.5, -1.0]))
    ours = encode(state, interfaces.JOINT_STATE)
    theirs = RCLPY_JOINT_STATE[:len(ours)]
    assert [b for i, b in enumerate(ours) if i not in JOINT_STATE_PADDING] == [
        b for i, b in enumerate(theirs) if i not in JOINT_STATE_PADDING]
    assert len(RCLPY_JOINT_STATE) - len(ours) == 8
    read = decode(RCLPY_JOINT_STATE, interfaces.JOINT_STATE)  # its 8 extra bytes ignored
    assert (read.name, list(read.position)) == (["a", "bc"], [0.5, -1.0])


def test_bytes_that_are_not_cdr_are_refused() -> None:
    with pytest.raises(InvalidArgumentError, match="not CDR"):
        decode(b"{}", interfaces.JOINT_STATE)
    with pytest.raises(InvalidArgumentError, match="not a CDR"):
        decode(RCLPY_JOINT_STATE[:30], interfaces.JOINT_STATE)


@pytest.mark.parametrize(("args", "says"), [
    (["--ros2", "--ros2-mirror", "arm"], "MODEL=TOPIC"),
    (["--ros2", "--ros-domain-id", "300"], "0 to 232"),
    (["--ros2", "--ros-namespace", "/1sim"], "not a ROS namespace"),
    (["--ros-namespace", "/sim"], "need --ros2"),
])
def test_bad_ros2_options_are_refused_before_anything_starts(args: list[str],
                                                             says: str) -> None:
    result = CliRunner().invoke(daemon_app, args)
    assert result.exit_code == 2
    assert says in result.output


def test_ros2_with_users_refuses_to_start_saying_why(tmp_path: Path) -> None:
    """Issue 46: it started silently, and then no ROS 2 caller could reach any service."""
    from support.users import users_file
    result = CliRunner().invoke(daemon_app, ["--ros2", "--users", str(users_file(tmp_path))],
                                env={"COLUMNS": "250"})
    assert result.exit_code == 2
    assert "--ros2 cannot be used with --users" in result.output
    assert "no user name" in result.output


def test_the_fast_tf_writer_equals_the_general_one() -> None:
    rng = np.random.default_rng(40)
    names = ["a", "ball_10", "arm/lbr_iiwa_link_3", "xyz", "é"]
    poses = rng.normal(size=(len(names), 7))
    general = new(interfaces.TF_MESSAGE, transforms=[
        new("geometry_msgs/msg/TransformStamped", header=header(12.345678901),
            child_frame_id=name, transform=new(
                "geometry_msgs/msg/Transform", translation=vector(*pose[:3]),
                rotation=new("geometry_msgs/msg/Quaternion", x=pose[3], y=pose[4],
                             z=pose[5], w=pose[6])))
        for name, pose in zip(names, poses, strict=True)])
    assert tf_cdr(names, poses, 12.345678901) == encode(general, interfaces.TF_MESSAGE)


def test_daemon_help_keeps_the_ros2_extras_brackets() -> None:
    """Issue 47: rich read "[ros2]" as markup and printed "needs the  extra"."""
    from typer.testing import CliRunner

    from galton.daemon.cli import app
    result = CliRunner().invoke(app, ["--help"], env={"COLUMNS": "250", "TERM": "dumb"})
    assert result.exit_code == 0
    assert "needs the [ros2] extra" in result.output
