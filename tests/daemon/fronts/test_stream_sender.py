"""The state streams' sender thread: a sample waiting behind a slow put is replaced by its
stream's next one, streams' samples go out in order, and close ends the thread."""

from __future__ import annotations

import threading

from galton.daemon.fronts.stream_sender import SampleSender

WAIT_S = 10.0


def test_a_slow_put_makes_waiting_samples_give_way_to_their_streams_latest() -> None:
    published: list[tuple[str, bytes]] = []
    putting, go_on = threading.Event(), threading.Event()

    def publish(topic: str, data: bytes) -> None:
        published.append((topic, data))
        putting.set()
        assert go_on.wait(WAIT_S)

    sender = SampleSender(publish)
    sender.send("states/a", b"a1")
    assert putting.wait(WAIT_S)  # a1 is being put, slowly
    for topic, data in (("states/a", b"a2"), ("states/b", b"b1"), ("states/a", b"a3")):
        sender.send(topic, data)
    go_on.set()
    sender.close()  # sends what is queued before it, then ends
    assert published == [("states/a", b"a1"), ("states/a", b"a3"), ("states/b", b"b1")]
    assert not sender._thread.is_alive()
