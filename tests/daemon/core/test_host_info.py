"""The ``host`` map of ``capabilities``: which machine a daemon runs on (issue 27)."""

from __future__ import annotations

import os
from pathlib import Path

from galton.client import Client
from galton.daemon.core.host_info import cpu_model, host_info
from galton.protocol import Capabilities

HOST_KEYS = {"cpu_model", "logical_cores", "memory_bytes", "os", "hostname", "python",
             "engines"}


def test_a_daemon_names_its_host(sim: Client) -> None:
    host = sim.capabilities().host
    assert set(host) == HOST_KEYS
    assert host["logical_cores"] == os.cpu_count()
    assert host["memory_bytes"] > 2**28 and host["cpu_model"]
    assert set(host["engines"]) == {"mujoco", "pybullet", "ode", "dartpy"}
    assert all(v != "not installed" for v in host["engines"].values())


def test_the_host_map_is_read_once() -> None:
    assert host_info() is host_info()


def test_the_cpu_model_comes_from_cpuinfo(tmp_path: Path) -> None:
    cpuinfo = tmp_path / "cpuinfo"
    cpuinfo.write_text("processor\t: 0\nmodel name\t: Test CPU @ 3.00GHz\nflags\t: fpu\n")
    assert cpu_model(cpuinfo) == "Test CPU @ 3.00GHz"
    assert cpu_model(tmp_path / "absent")  # a fallback, never empty


def test_capabilities_parse_without_host_and_with_fields_not_known_here() -> None:
    body = {"engine": "mujoco", "engine_version": "3", "protocol_version": 1,
            "body_shapes": ["sphere"], "model_formats": [], "features": ["spawn"]}
    old = Capabilities.from_wire(body)
    assert old.host == {} and old.body_shapes == ("sphere",)
    newer = Capabilities.from_wire({**body, "host": {"hostname": "a"},
                                    "zmq": {"control": ["ipc:///tmp/x"]}})
    assert newer.host == {"hostname": "a"}
    assert newer.to_wire()["host"] == {"hostname": "a"}
