"""The live page's parts without a browser (tests/client/view/test_view_browser.py draws it in one):
side worlds followed as ghosts, compare's score charted, a prediction drawn, operator
actions, links and meshes drawn as their shapes, on the session's MuJoCo daemon."""

from __future__ import annotations

import socket
import time
from collections.abc import Iterator

import numpy as np
import pytest

from galton.client import Client, EmbeddedDaemon, meshes, spheres

viser = pytest.importorskip("viser", reason="the [view] extra is not installed")
from galton.client.view.live import LiveView  # noqa: E402

WAIT_S = 20.0


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@pytest.fixture
def page(mujoco_sim: Client, daemons: dict[str, EmbeddedDaemon]) -> Iterator[LiveView]:
    mujoco_sim.spawn(spheres(["a", "b"], [[0, 0, 1], [0.3, 0, 1]], radius=0.05,
                             tags=["red"]))
    mujoco_sim.step(1)
    server = viser.ViserServer(host="127.0.0.1", port=_free_port(), verbose=False)
    with Client(mujoco_sim.instance, daemons["mujoco"].endpoint, timeout=WAIT_S) as client:
        view = LiveView(client, server, rate=20, operator=True)
        try:
            yield view
        finally:
            view.close()
            server.stop()


def _until(page: LiveView, done: object) -> None:
    """Wait on the page's wake event (a sample or an event came) until ``done()``."""
    deadline = time.monotonic() + WAIT_S
    while not done():  # type: ignore[operator]
        assert page.wake.wait(max(0.0, deadline - time.monotonic())), "nothing came"
        page.wake.clear()


def test_a_fork_is_drawn_as_a_ghost_and_goes_with_its_world(
        mujoco_sim: Client, page: LiveView) -> None:
    _until(page, lambda: page.live.draw() is not None or page.live.drawing.names)
    assert page.live.drawing.names == ("a", "b")
    mujoco_sim.fork_world("ahead")
    try:
        page._follow_side_worlds()
        ghost = page.ghosts["ahead"]
        _until(page, lambda: ghost.draw() is not None)
        assert ghost.drawing.names == ("a", "b") and ghost.drawing.opacity is not None
    finally:
        mujoco_sim.delete_world("ahead")
    page._follow_side_worlds()
    assert "ahead" not in page.ghosts


def test_compare_scores_are_charted_and_a_prediction_is_drawn(
        mujoco_sim: Client, page: LiveView) -> None:
    _until(page, lambda: page.live.draw() is not None or page.live.drawing.names)
    observed = mujoco_sim.get_states(["a"]).poses + np.array([[0.1, 0, 0, 0, 0, 0, 0]])
    score = mujoco_sim.compare(["a"], observed).score
    _until(page, lambda: page.scores_seen == 1)
    page._draw_scores()
    assert page.chart.data[1].tolist() == [pytest.approx(score)]
    page._act(page._predict)
    assert page.message.content == ""
    assert page.prediction.names == ("a", "b")
    page._act(page._imagine)  # 8 futures of 1 s, every 50 ms: 20 segments a body each
    assert page.message.content == "" and page.future_segments == 8 * 2 * 20
    step = mujoco_sim.status().step
    page._act(page._step)
    assert mujoco_sim.status().step == step + 100


CRATE = """<robot name="crate"><link name="base">
  <inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/>
  </inertial>
  <collision><origin xyz="0 0 0.1" rpy="0 0 1.5707963267948966"/>
    <geometry><box size="0.2 0.4 0.6"/></geometry></collision>
</link></robot>"""


def test_a_loaded_models_link_is_drawn_as_its_collision_shapes(
        mujoco_sim: Client, page: LiveView) -> None:
    [crate] = mujoco_sim.load_model("urdf", text=CRATE, prefix="u_")
    _until(page, lambda: page.live.draw() is not None and crate in page.live.drawing.names)
    vertices = page.live.drawing.vertices_of(crate)  # turned a quarter: x and y swap
    np.testing.assert_allclose(vertices.min(axis=0), [-0.2, -0.1, -0.2], atol=1e-5)
    np.testing.assert_allclose(vertices.max(axis=0), [0.2, 0.1, 0.4], atol=1e-5)
    # A spawned ball keeps its own shape.
    assert np.ptp(page.live.drawing.vertices_of("a"), axis=0) == pytest.approx([0.1] * 3, abs=1e-3)


# A square pyramid off its body's origin: five vertices, where its box would have eight.
PYRAMID = (np.array([[-0.1, -0.1, 0.0], [0.1, -0.1, 0.0], [0.1, 0.1, 0.0], [-0.1, 0.1, 0.0],
                     [0.0, 0.0, 0.2]]) + np.array([0.02, 0.0, -0.05]),
           np.array([[0, 2, 1], [0, 3, 2], [0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]))


def test_a_spawned_mesh_is_drawn_as_its_triangles(mujoco_sim: Client, page: LiveView) -> None:
    vertices, faces = PYRAMID
    mujoco_sim.spawn(meshes(["p1", "p2"], [[0, 1, 0.5], [0.5, 1, 0.5]], vertices, faces,
                            static=True, tags=["green"]))
    _until(page, lambda: page.live.draw() is not None and "p2" in page.live.drawing.names)
    np.testing.assert_allclose(page.live.drawing.vertices_of("p1"), vertices, atol=1e-6)
    np.testing.assert_allclose(page.live.drawing.vertices_of("p2"), vertices, atol=1e-6)
    # A loaded model's mesh link: MuJoCo keeps its triangles, so it is drawn as them.
    [holder] = mujoco_sim.load_model("mjcf", text=MJCF_TETRAHEDRON, prefix="t_")
    _until(page, lambda: page.live.draw() is not None and holder in page.live.drawing.names)
    drawn = page.live.drawing.vertices_of(holder)
    assert len(drawn) == 4  # not a box's 8
    np.testing.assert_allclose(sorted(np.round(drawn, 5).tolist()), TETRAHEDRON_IN_BODY,
                               atol=1e-5)


MJCF_TETRAHEDRON = """<mujoco><asset><mesh name="tet" vertex="0 0 0  0.2 0 0  0 0.1 0  0 0 0.3"
  face="0 2 1  0 1 3  0 3 2  1 2 3"/></asset><worldbody><body name="holder" pos="0 -1 1">
  <geom type="mesh" mesh="tet" pos="0.1 0 0"/></body></worldbody></mujoco>"""
TETRAHEDRON_IN_BODY = [[0.1, 0.0, 0.0], [0.1, 0.0, 0.3], [0.1, 0.1, 0.0], [0.3, 0.0, 0.0]]
