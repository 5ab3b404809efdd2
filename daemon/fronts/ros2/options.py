"""What ``--ros2`` and its options ask of the ROS 2 front (importable without rosbags)."""

from __future__ import annotations

import importlib.util
from dataclasses import dataclass, field

from galton.daemon.fronts.ros2.rmw_zenoh import check_namespace
from galton.protocol import FeatureUnsupportedError, InvalidArgumentError

MAX_DOMAIN_ID = 232  # ROS 2 domain ids are 0-232 (0-101 portable)


@dataclass(frozen=True)
class Ros2Options:
    """``--ros2 [--ros-domain-id N] [--ros-namespace NS] [--ros2-mirror MODEL=TOPIC]``."""

    domain: int = 0
    namespace: str = ""
    mirrors: dict[str, str] = field(default_factory=dict)  # model root -> JointState topic
    clock_rate_hz: float = 200.0
    tf_rate_hz: float = 20.0
    max_request_bytes: int = 16 * 1024 * 1024  # one ROS request (the daemon's limit's)


def parse_mirror(text: str) -> tuple[str, str]:
    """``MODEL=/joint_states`` -> (model, topic)."""
    model, sep, topic = text.partition("=")
    if not sep or not model or not topic or " " in topic:
        raise InvalidArgumentError(f"--ros2-mirror {text!r}: give MODEL=TOPIC, e.g. "
                                   "arm=/joint_states (MODEL: a loaded model's root entity)")
    return model, topic


def ros2_options(domain: int, namespace: str, mirrors: list[str]) -> Ros2Options:
    """The front's options, checked; without the ``[ros2]`` extra, FEATURE_UNSUPPORTED."""
    if importlib.util.find_spec("rosbags") is None:
        raise FeatureUnsupportedError("--ros2 needs the [ros2] extra (rosbags): pip install "
                                      "'galton-bridge[daemon,ros2]'")
    if not 0 <= domain <= MAX_DOMAIN_ID:
        raise InvalidArgumentError(f"--ros-domain-id {domain}: ROS 2 domain ids are 0 to "
                                   f"{MAX_DOMAIN_ID}")
    return Ros2Options(domain=domain, namespace=check_namespace(namespace),
                       mirrors=dict(parse_mirror(text) for text in mirrors))
