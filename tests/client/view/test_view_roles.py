"""The view under ``--users`` (docs/SECURITY.md): a viewer may watch the world through a
state stream, and its page offers no buttons; an operator's does."""

from __future__ import annotations

import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest
from support.users import ALICE, BOB, users_file

from galton.client import Client, EmbeddedDaemon, spheres
from galton.protocol import AccessDeniedError
from galton.protocol.keys import VIEWER_ID_PREFIX

pytest.importorskip("viser", reason="the [view] extra is not installed")
INSTANCE = "viewed"
WAIT_S = 20.0


@pytest.fixture(scope="module")
def secured(tmp_path_factory: pytest.TempPathFactory) -> Iterator[EmbeddedDaemon]:
    folder: Path = tmp_path_factory.mktemp("users")
    with EmbeddedDaemon("mujoco", instance=INSTANCE,
                        extra_args=["--users", str(users_file(folder))]) as daemon:
        yield daemon


def test_a_viewer_streams_the_world_but_gets_no_buttons(secured: EmbeddedDaemon) -> None:
    from galton.client.view.live import may_operate
    with Client(INSTANCE, secured.endpoint, timeout=WAIT_S, credentials=ALICE) as operator:
        operator.load_world("mujoco")
        operator.spawn(spheres(["ball"], [[0, 0, 1]], radius=0.05, tags=["red"]))
        operator.step(20)
        assert may_operate(operator)
        viewer_id = f"{VIEWER_ID_PREFIX}{uuid.uuid4().hex}"
        with Client(INSTANCE, secured.endpoint, timeout=WAIT_S, credentials=BOB,
                    client_id=viewer_id) as viewer:
            assert not may_operate(viewer)
            assert [info.name for info in viewer.list()] == ["ball"]
            with viewer.stream_states(rate=20, timeout=WAIT_S) as stream:
                sample = stream.next()
            assert sample.names == ("ball",) and sample.step == 20
            with pytest.raises(AccessDeniedError):
                viewer.request("step", {"count": 1}, timeout=2.0).raise_for_code()
        assert operator.status().step == 20  # nothing the viewer did moved the world
