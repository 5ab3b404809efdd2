"""The ROS 2 front: simulation_interfaces services, /clock, /tf and joint mirroring in
rmw_zenoh's wire format, on the daemon's own Zenoh session.

It reaches the physics thread only as the Zenoh front does: it hands ``Call`` objects
(msgpack native requests) to the daemon's ``dispatch`` and reads their replies. A service
request runs as a handler (daemon/fronts/ros2/services.py) that yields native requests; each reply
is sent back into the handler on the front's one reply thread, so no thread waits for
physics and the physics thread does no ROS work. Topics run on one thread of their own
(daemon/fronts/ros2/topics.py).
"""

from __future__ import annotations

import itertools
import logging
import queue
import re
import threading
from collections.abc import Callable
from typing import Any

import zenoh

from galton.daemon.core.calls import Call, CallPort
from galton.daemon.fronts.base import EVENTS, Front
from galton.daemon.fronts.memory import after_request_of
from galton.daemon.fronts.ros2 import codes, rmw_zenoh
from galton.daemon.fronts.ros2.action import SimulateStepsServer
from galton.daemon.fronts.ros2.interfaces import dds_type_name, service_type, type_hash
from galton.daemon.fronts.ros2.messages import decode, encode, new
from galton.daemon.fronts.ros2.native import Handler, NativeRequest, Refusal
from galton.daemon.fronts.ros2.options import Ros2Options
from galton.daemon.fronts.ros2.services import HANDLERS
from galton.daemon.fronts.ros2.topics import Publisher, TopicLoop
from galton.protocol import GaltonError, Reply, decode_reply, encode_request

log = logging.getLogger("galton.daemon.fronts.ros2")


def node_name(instance: str) -> str:
    """The node's name: the instance name with what ROS forbids (``-``, ``.``) as ``_``."""
    name = re.sub(r"[^A-Za-z0-9_]", "_", instance)
    return name if name[0].isalpha() else f"galton_{name}"


def service_name(type_name: str) -> str:
    """``StepSimulation`` -> ``step_simulation`` (the names Gazebo and Isaac Sim use)."""
    return re.sub(r"(?<!^)(?=[A-Z])", "_", type_name).lower()


class Ros2Front(Front):
    """One ROS 2 node, named after the daemon's instance, with a server per service: a
    ``Front`` (daemon/fronts/base.py) built on the Zenoh front's session, serving from
    ``open``, and publishing its own topics (so the core's samples are not its business)."""

    def __init__(self, session: zenoh.Session, node: str, options: Ros2Options) -> None:
        self.session = session
        self.options = options
        self.identity = rmw_zenoh.NodeIdentity(
            options.domain, str(session.info.zid()), 0,
            rmw_zenoh.check_namespace(options.namespace), node_name(node))
        self._entity_ids = itertools.count(1)
        self._replies: queue.SimpleQueue[tuple[Callable[[Reply], None], bytes] | None] = \
            queue.SimpleQueue()
        self._reply_thread = threading.Thread(target=self._take_replies, name="ros2-replies",
                                              daemon=True)
        self._declared: list[Any] = []
        self._wake_topics: Callable[[], None] = lambda: None  # the topic loop's, once made
        self._core: CallPort | None = None  # set by open()
        self.action: SimulateStepsServer | None = None
        self.topics: TopicLoop | None = None

    def open(self, core: CallPort) -> None:
        """Start serving: the node's token, a server per service, the action, the topics;
        their requests go to ``core.dispatch``."""
        self._core = core
        self._reply_thread.start()
        self._declared.append(self.session.liveliness().declare_token(
            self.identity.node_token()))
        for name, handler in HANDLERS.items():
            self._serve(name, handler)
        self.action = SimulateStepsServer(self)
        self.topics = TopicLoop(self, self.options)
        self._wake_topics = self.topics.wake

    def ready_words(self) -> str:
        """What the daemon's ready line says of this front: its node, domain and services
        (the action's three counted apart)."""
        node = self.qualified(self.identity.node)
        return (f"ros2_node={node} ros2_domain={self.identity.domain} "
                f"ros2_services={len(HANDLERS)} ros2_actions=1")

    def qualified(self, name: str) -> str:
        """A name in the node's namespace (an absolute name, ``/clock``, stays as it is)."""
        return rmw_zenoh.qualified_name(self.identity.namespace, name)

    def declare_entity(self, kind: str, qualified: str, ros_type: str) -> str:
        """Announce a publisher, subscription or server by its liveliness token; return the
        entity's key expression."""
        dds, hashed = dds_type_name(ros_type), type_hash(ros_type)
        qos = rmw_zenoh.SERVICE_QOS if kind == rmw_zenoh.SERVICE_SERVER else \
            rmw_zenoh.TOPIC_QOS
        token = self.identity.entity_token(next(self._entity_ids), kind, qualified, dds,
                                           hashed, qos)
        self._declared.append(self.session.liveliness().declare_token(token))
        return rmw_zenoh.key_expr(self.identity.domain, qualified, dds, hashed)

    def _serve(self, name: str, handler: Handler) -> None:
        response_type = f"{service_type(name)}_Response"
        self.serve_raw(self.qualified(f"{self.identity.node}/{service_name(name)}"),
                       service_type(name),
                       lambda request, answer: self.run(handler(request), answer,
                                                        response_type))

    def serve_raw(self, qualified: str, ros_type: str,
                  take: Callable[[Any, Callable[[Any], None]], None]) -> None:
        """A service server: ``take(request, answer)`` gets each decoded request and calls
        ``answer(response)`` exactly once, from any thread, whenever it is ready."""
        key = rmw_zenoh.key_expr(self.identity.domain, qualified, dds_type_name(ros_type),
                                 type_hash(ros_type))
        request_type, response_type = f"{ros_type}_Request", f"{ros_type}_Response"

        def on_query(query: zenoh.Query) -> None:
            read = _read_query(query, request_type, self.options.max_request_bytes)
            if read is not None:
                self._wake_topics()  # a request may move the clock: /clock follows at once
                attachment, request = read
                take(request, lambda response: _answer(query, attachment, response,
                                                       response_type))
        self._declared.append(self.session.declare_queryable(key, on_query, complete=True))
        self.declare_entity(rmw_zenoh.SERVICE_SERVER, qualified, ros_type)  # then announce

    def publisher(self, name: str, ros_type: str) -> Publisher:
        return Publisher(self, name, ros_type)

    def run(self, steps: Any, finish: Callable[[Any], None], response_type: str,
            reply: Reply | None = None) -> None:
        """Advance a handler by one native request (or to its response)."""
        try:
            asked: NativeRequest = steps.send(reply) if reply is not None else next(steps)
        except StopIteration as done:
            finish(done.value)
            return
        except Refusal as refusal:
            finish(refused(response_type, refusal.code, refusal.message))
            return
        except Exception as exc:  # a handler's bug must still answer its caller
            log.exception("ROS 2 handler for %s failed", response_type)
            finish(refused(response_type, codes.OPERATION_FAILED, f"{type(exc).__name__}"))
            return
        op, args = asked
        self.call(op, args, lambda answer: self.run(steps, finish, response_type, answer))

    def call(self, op: str, args: dict[str, Any], then: Callable[[Reply], None],
             client: str | None = None) -> None:
        """One native request through the daemon's own dispatch; ``then`` gets its Reply
        on the front's reply thread, so ROS-side work (CDR, the next request of a handler)
        never holds the physics thread that answered. ``client``: the id it is sent as (a
        goal's, so that ``lose`` can end its step)."""
        assert self._core is not None  # requests are served from open() on
        self._core.dispatch(Call(op, encode_request(op, args, client),
                                 lambda data: self._replies.put((then, data))))

    def lose(self, client: str) -> None:
        """End the step request sent as ``client`` now, running or waiting (the core ends a
        gone client's step between two steps): how a cancelled goal stops at once."""
        if self._core is not None:
            self._core.lose_client(client)

    def _take_replies(self) -> None:
        while (item := self._replies.get()) is not None:
            then, data = item
            try:
                then(decode_reply(data))
            except Exception:  # one bad continuation must not end the others
                log.exception("ROS 2 front: a reply's continuation failed")

    def publish(self, topic: str, data: bytes) -> None:
        """Not this front's: /clock, /tf and joint states are read by its own topic loop,
        which an event wakes (the clock may start moving: play, a step, a new world)."""
        if topic == EVENTS:
            self._wake_topics()

    def client_alive(self, client: str) -> bool | None:
        """Not this front's to say: a goal's step ends by ``lose`` (a cancel), and a ROS 2
        caller holds no stream or lease."""
        return None

    def withdraw(self) -> None:
        """The node's token goes at ``close``, after pending requests are answered."""

    def close(self) -> None:
        """Stop the topics and the reply thread, then undeclare (nothing, if never opened)."""
        if self.topics is not None:
            self.topics.close()
        if self._reply_thread.is_alive():
            self._replies.put(None)
            self._reply_thread.join(timeout=5)
        for declared in reversed(self._declared):
            declared.undeclare()
        self._declared.clear()


def _read_query(query: zenoh.Query, request_type: str, max_bytes: int
                ) -> tuple[rmw_zenoh.Attachment, Any] | None:
    """The attachment and decoded request of a query; one that cannot be read gets an error
    reply (rcl would drop it), never silence, and None. One over ``max_bytes`` is refused
    before Python copies it; after a big one the heap's free pages go back (memory.py)."""
    size = len(query.payload) if query.payload is not None else 0
    after_request_of(size)
    try:
        if query.attachment is None:
            raise GaltonError("the query has no rmw_zenoh attachment (sequence number, "
                              "timestamp, GID): docs/ROS2.md")
        attachment = rmw_zenoh.Attachment.decode(query.attachment.to_bytes())
        if size > max_bytes:
            raise GaltonError(f"the request is {size} bytes; at most {max_bytes} (the "
                              "daemon's max_request_bytes)")
        payload = query.payload.to_bytes() if query.payload is not None else b""
        return attachment, decode(payload, request_type)
    except GaltonError as error:
        with query:
            query.reply_err(str(error))
        return None


def _answer(query: zenoh.Query, attachment: rmw_zenoh.Attachment, response: Any,
            response_type: str) -> None:
    """Reply with the response and the request's sequence number and GID, then finish."""
    try:
        query.reply(query.key_expr, encode(response, response_type),
                    attachment=attachment.reply().encode())
    finally:
        query.drop()


def refused(response_type: str, code: int, message: str) -> Any:
    """A response with only its Result set (GetSimulatorFeatures has none: left empty)."""
    result = new("simulation_interfaces/msg/Result", result=code, error_message=message)
    try:
        return new(response_type, result=result)
    except KeyError:
        return new(response_type)
