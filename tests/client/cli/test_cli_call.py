"""galton-client call OP JSON, and the real console command run as a subprocess."""

from __future__ import annotations

import json
import re
import shlex
import subprocess
from pathlib import Path

import numpy as np
import pytest
from support.cli import CONSOLE_COMMAND, flat, invoke, run, target_of

from galton.client import Client, EmbeddedDaemon, spheres
from galton.client.cli.call import unpacked
from galton.client.cli.common import package_version
from galton.protocol import pack_f64

EVENT_WAIT_S = 1.0  # per try: the subscription may take a moment to reach the daemon
EVENT_TRIES = 30


@pytest.fixture
def target(mujoco_sim: Client, daemons: dict[str, EmbeddedDaemon]) -> list[str]:
    return target_of(daemons["mujoco"])


def test_call_packs_nested_poses_and_unpacks_the_result(target: list[str]) -> None:
    group = {"shape": "sphere", "size": [0.05], "names": ["a", "b"],
             "poses": [[0, 0, 1, 0, 0, 0, 1], [1, 0, 1, 0, 0, 0, 1]]}
    assert invoke([*target, "call", "spawn", json.dumps({"groups": [group]})]) == {
        "names": ["a", "b"]}
    poses = [[3, 0, 1, 0, 0, 0, 1]]
    assert invoke([*target, "call", "set_states",
                   json.dumps({"names": ["b"], "poses": poses})]) == {"count": 1}
    states = invoke([*target, "call", "get_states", '{"names": ["a", "b"]}'])
    assert states["poses"] == [[0, 0, 1, 0, 0, 0, 1], *poses]
    assert states["twists"] == [[0] * 6, [0] * 6]


def test_call_with_no_args_and_the_whole_reply(target: list[str]) -> None:
    assert invoke([*target, "call", "status"])["engine"] == "mujoco"
    reply = invoke([*target, "call", "step", '{"count": 4}', "--reply"])
    assert reply["code"] == 0 and reply["code_name"] == "OK" and reply["step"] == 4


def test_call_reaches_an_operation_with_no_command_of_its_own(target: list[str]) -> None:
    group = {"shape": "sphere", "size": [0.25], "names": ["near", "far"], "static": True,
             "poses": [[0, 0, 1, 0, 0, 0, 1], [5, 0, 1, 0, 0, 0, 1]]}
    invoke([*target, "call", "spawn", json.dumps({"groups": [group]})])
    region = [[-1, -1, 0], [1, 1, 2]]  # nested rows, packed as the wire's points
    assert invoke([*target, "call", "get_entities",
                   json.dumps({"pattern": "*a*", "region": region})]) == {"names": ["near"]}


def test_a_failed_call_names_the_wire_code(target: list[str]) -> None:
    result = run([*target, "call", "delete", '{"names": ["ghost"]}'])
    assert result.exit_code == 1 and result.stdout == ""
    assert result.stderr.startswith("galton-client: NOT_FOUND (1): ")
    whole = run([*target, "call", "stepp", "--reply"])
    assert whole.exit_code == 1 and "UNKNOWN_OPERATION (8)" in whole.stderr
    assert json.loads(whole.stdout)["code_name"] == "UNKNOWN_OPERATION"


def test_unpacked_turns_every_bin_into_numbers() -> None:
    pose = [0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    result = {"poses": pack_f64(np.array([pose])), "other": pack_f64(np.array([1.5, 2.5])),
              "odd": b"\x01\x02", "nested": [{"twists": pack_f64(np.zeros((1, 6)))}]}
    assert unpacked(result) == {"poses": [pose], "other": [1.5, 2.5], "odd": "0102",
                                "nested": [{"twists": [[0.0] * 6]}]}


@pytest.mark.parametrize("args", ["{oops", "[1, 2]"])
def test_call_args_must_be_a_json_object(target: list[str], args: str) -> None:
    result = run([*target, "call", "list", args])
    assert result.exit_code == 2 and "ARGS" in flat(result.output)


def console(*args: str, timeout: float = 60.0) -> subprocess.CompletedProcess[str]:
    return subprocess.run([CONSOLE_COMMAND, *args], capture_output=True, text=True,
                          timeout=timeout, check=False)


def test_console_command_version_and_call(target: list[str]) -> None:
    assert console("--version").stdout.strip() == f"galton-client {package_version()}"
    done = console(*target, "call", "list", '{"kind": "static"}')
    assert done.returncode == 0 and json.loads(done.stdout) == {"entities": []}


def test_console_command_error_is_one_line_on_stderr(target: list[str]) -> None:
    done = console(*target, "delete", "ghost")
    assert done.returncode == 1 and done.stdout == ""
    assert done.stderr.startswith("galton-client: NOT_FOUND (1): no entity")
    assert len(done.stderr.splitlines()) == 1


def test_console_command_shape_choice_fails_first() -> None:
    done = console("--connect", "tcp/127.0.0.1:1", "spawn", "cube", "a")
    assert done.returncode == 2 and "is not one of 'sphere'" in flat(done.stderr)


def test_events_prints_a_scene_change(mujoco_sim: Client, target: list[str]) -> None:
    """The events command, run for real: it says when it listens; a spawn then shows up."""
    process = subprocess.Popen([CONSOLE_COMMAND, *target, "events", "--count", "1", "--json"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert process.stderr is not None and "listening" in process.stderr.readline()
        for attempt in range(EVENT_TRIES):
            mujoco_sim.spawn(spheres([f"ping_{attempt}"], [[attempt, 0, 1]], radius=0.05))
            try:
                out, _ = process.communicate(timeout=EVENT_WAIT_S)
                break
            except subprocess.TimeoutExpired:
                continue
        else:
            pytest.fail("no event printed")
    finally:
        process.kill()
        process.wait()
    event = json.loads(out)
    assert event["kind"] == "scene" and event["op"] == "spawn" and event["seq"] >= 1


def readme_cli_commands() -> list[list[str]]:
    """The galton-client lines of the README's CLI section's shell snippets."""
    text = (Path(__file__).parents[3] / "README.md").read_text()
    section = text.split("\n## CLI\n", 1)[1].split("\n## ", 1)[0]
    snippets = re.findall(r"```sh\n(.*?)```", section, flags=re.DOTALL)
    return [shlex.split(line)[1:] for snippet in snippets for line in snippet.splitlines()
            if line.startswith("galton-client ")]


def test_the_readme_cli_snippets_run(target: list[str]) -> None:
    invoke([*target, "spawn", "sphere", "ball", "--json"])
    lines = readme_cli_commands()
    assert lines
    for args in lines:
        result = run([*target, *args])
        assert result.exit_code == 0, (args, result.output)
