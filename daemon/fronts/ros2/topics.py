"""/clock, /tf and joint mirroring for the ROS 2 front.

One thread publishes ``/clock`` (rosgraph_msgs/Clock, the sim time, so nodes with
``use_sim_time`` follow it) each time it moves, at most ``clock_rate_hz``, read from the
``status`` the daemon answers without the physics thread; and ``/tf`` (tf2_msgs/TFMessage:
each entity's pose in ``world``) at most ``tf_rate_hz`` while the step moves, from
``get_states``. A mirror subscribes to sensor_msgs/JointState and sets its model's joints
from each message; while one is being applied only the newest waiting message is kept, so
the joints lag the robot by at most one message.
"""

from __future__ import annotations

import itertools
import logging
import threading
import time
from typing import TYPE_CHECKING, Any

import zenoh

from galton.daemon.fronts.ros2 import rmw_zenoh
from galton.daemon.fronts.ros2.interfaces import CLOCK, JOINT_STATE, TF_MESSAGE
from galton.daemon.fronts.ros2.messages import decode, encode, new, packed, rows, tf_cdr, time_msg
from galton.protocol import GaltonError, Reply, ResultCode

if TYPE_CHECKING:
    from galton.daemon.fronts.ros2.front import Ros2Front
    from galton.daemon.fronts.ros2.options import Ros2Options

log = logging.getLogger("galton.daemon.fronts.ros2")
ANSWER_WAIT_S = 0.5  # how long the topic thread waits for one native reply
CLOCK_REPEAT_S = 1.0  # a still clock is published again this often (for late joiners)
# A clock that has not moved for STILL_AFTER_S is looked at every IDLE_POLL_S, not at the
# clock rate (200 Hz of status was ~9 % of a core for an idle daemon): an event (play, a
# world loaded) or a ROS 2 request wakes the thread at once, so only a native step of a
# paused world reaches /clock up to IDLE_POLL_S late.
STILL_AFTER_S, IDLE_POLL_S = 0.5, 0.1


class Publisher:
    """A ROS publisher: its liveliness token, a Zenoh publisher, rmw_zenoh attachments."""

    def __init__(self, front: Ros2Front, name: str, ros_type: str) -> None:
        key = front.declare_entity(rmw_zenoh.PUBLISHER, front.qualified(name), ros_type)
        self.ros_type = ros_type
        self._publisher = front.session.declare_publisher(key)
        front._declared.append(self._publisher)
        self._gid = rmw_zenoh.new_gid()
        self._sequence = itertools.count(1)

    def put(self, message: Any) -> None:
        self.put_cdr(encode(message, self.ros_type))

    def put_cdr(self, data: bytes) -> None:
        """Publish a message already in CDR."""
        attachment = rmw_zenoh.Attachment(next(self._sequence), time.time_ns(), self._gid)
        self._publisher.put(data, attachment=attachment.encode())


class TopicLoop:
    """The thread that publishes /clock and /tf, and the joint mirrors."""

    def __init__(self, front: Ros2Front, options: Ros2Options) -> None:
        self.front = front
        self.clock = front.publisher("/clock", CLOCK)
        self.tf = front.publisher("/tf", TF_MESSAGE)
        self.mirrors = [Mirror(front, model, topic) for model, topic in options.mirrors.items()]
        self._clock_period = 1.0 / options.clock_rate_hz
        self._tf_period = 1.0 / options.tf_rate_hz
        self._stop = threading.Event()
        self._wake = threading.Event()  # something may move the clock: look now
        self._thread = threading.Thread(target=self._run, name="ros2-topics", daemon=True)
        self._thread.start()

    def _ask(self, op: str, args: dict[str, Any] | None = None) -> Reply | None:
        """One native request, waited for on this thread (None if unanswered)."""
        answered = threading.Event()
        box: list[Reply] = []

        def then(reply: Reply) -> None:
            box.append(reply)
            answered.set()
        self.front.call(op, args or {}, then)
        answered.wait(ANSWER_WAIT_S)
        return box[0] if box and box[0].ok else None

    def wake(self) -> None:
        """Look at the clock now (an event came, or a ROS 2 request): any thread."""
        self._wake.set()

    def _run(self) -> None:
        last_time, last_sent, tf_step, next_tf = -1.0, 0.0, -1, 0.0
        moved_at, period = time.monotonic(), self._clock_period
        while not self._stop.is_set():
            if self._wake.wait(period):
                self._wake.clear()
            if self._stop.is_set():
                return
            try:
                status = self._ask("status")
                if status is None:
                    continue
                now, sim_time = time.monotonic(), status.result["sim_time"]
                if sim_time != last_time or status.result["state"] == "playing":
                    moved_at = now
                period = (self._clock_period if now - moved_at < STILL_AFTER_S
                          else IDLE_POLL_S)
                if sim_time != last_time or now - last_sent >= CLOCK_REPEAT_S:
                    self.clock.put(new(CLOCK, clock=time_msg(sim_time)))
                    last_time, last_sent = sim_time, now
                if now >= next_tf and status.result["step"] != tf_step:
                    next_tf = now + self._tf_period
                    tf_step = status.result["step"] if self._publish_tf() else -1
            except Exception:  # the topics must outlive any one bad sample
                log.exception("ROS 2 topic thread")

    def _publish_tf(self) -> bool:
        states = self._ask("get_states")
        if states is None or not states.result["names"]:
            return False
        self.tf.put_cdr(tf_cdr(states.result["names"], rows(states.result["poses"], 7),
                               states.sim_time))
        return True

    def close(self) -> None:
        self._stop.set()
        self._wake.set()
        self._thread.join(timeout=5)
        for mirror in self.mirrors:
            mirror.close()


class Mirror:
    """``--ros2-mirror MODEL=TOPIC``: the model's joints follow JointState messages.
    MODEL is a loaded model's root entity, or the name it was spawned with over ROS (its
    entities are then ``MODEL/...``); it may be loaded after the daemon starts."""

    def __init__(self, front: Ros2Front, model: str, topic: str) -> None:
        self.front, self.model, self.topic = front, model, topic
        key = front.declare_entity(rmw_zenoh.SUBSCRIPTION, front.qualified(topic),
                                   JOINT_STATE)
        self._lock = threading.Lock()
        self._pending: Any = None
        self._busy = False
        self._joints: list[str] | None = None  # the model's 1-DOF joints, once asked
        self.applied = 0  # messages applied
        self.superseded = 0  # messages replaced by a newer one before being applied
        self.refused = 0  # messages the daemon refused (unknown model, bad values)
        self._last_warning = ""  # a refusal is logged when it differs from the last one
        self._subscriber = front.session.declare_subscriber(key, self._on_sample)

    def _on_sample(self, sample: zenoh.Sample) -> None:
        try:
            message = decode(sample.payload.to_bytes(), JOINT_STATE)
        except GaltonError as error:
            log.warning("%s: %s", self.topic, error)
            return
        with self._lock:
            if self._pending is not None:
                self.superseded += 1
            self._pending = message
            if self._busy:
                return
            self._busy = True
        self._next()

    def _next(self) -> None:
        """Apply the newest waiting message, or go idle (on the front's reply thread, or
        the subscriber's)."""
        with self._lock:
            message, self._pending = self._pending, None
            if message is None:
                self._busy = False
                return
        if self._joints is None:
            self.front.call("joints", {}, lambda reply: self._mapped(reply, message))
        else:
            self._apply(message)

    def _mapped(self, reply: Reply, message: Any) -> None:
        if not reply.ok:
            self._refused(reply)
            return
        model, below = self.model, f"{self.model}/"
        self._joints = [joint["name"] for joint in reply.result["joints"]
                        if joint["type"] in ("revolute", "prismatic")
                        and (joint["model"] == model or joint["model"].startswith(below))]
        if not self._joints:
            self._joints = None
            self.refused += 1
            self._warn(f"no model {self.model!r} with revolute or prismatic joints (yet)")
            self._next()
            return
        self._apply(message)

    def _apply(self, message: Any) -> None:
        names, positions, velocities = [], [], []
        has_velocity = len(message.velocity) == len(message.name)
        for index, name in enumerate(message.name):
            joint = self._joint_for(name)
            if joint is not None and index < len(message.position):
                names.append(joint)
                positions.append(float(message.position[index]))
                velocities.append(float(message.velocity[index]) if has_velocity else 0.0)
        if not names:
            self.refused += 1
            self._next()
            return
        args: dict[str, Any] = {"names": names, "positions": packed([positions])}
        if has_velocity:
            args["velocities"] = packed([velocities])
        self.front.call("set_joint_states", args, self._applied)

    def _joint_for(self, name: str) -> str | None:
        """The model's joint a message's name means: the same name, or the one name that
        ends with it (the model was loaded with a prefix)."""
        joints = self._joints or []
        if name in joints:
            return name
        ends = [joint for joint in joints if joint.endswith(name)]
        return ends[0] if len(ends) == 1 else None

    def _applied(self, reply: Reply) -> None:
        if reply.ok:
            self.applied += 1
            self._next()
        else:
            self._refused(reply)

    def _refused(self, reply: Reply) -> None:
        self.refused += 1
        if reply.code == ResultCode.NOT_FOUND:
            self._joints = None  # the model was deleted or reloaded: ask again next time
        self._warn(reply.message)
        self._next()

    def _warn(self, message: str) -> None:
        """Log a refusal once, not at the rate of the messages (100 Hz would flood)."""
        if message != self._last_warning:
            self._last_warning = message
            log.warning("mirror %s <- %s: %s", self.model, self.topic, message)

    def close(self) -> None:
        self._subscriber.undeclare()
