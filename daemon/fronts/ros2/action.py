"""The SimulateSteps action, as rmw_zenoh carries an action: three services under
``<name>/_action/`` (``send_goal``, ``get_result``, ``cancel_goal``) and two topics
(``feedback``, ``status``).

A goal is accepted when ``steps`` is at least 1 and runs as native ``step`` requests of at
most ``ceil(steps / 100)`` steps each (feedback after each chunk: every step for up to 100
steps); it ends SUCCEEDED with RESULT_OK, ABORTED with the step's failure (OPERATION_FAILED
while playing, as the standard says), or CANCELED. Each goal's steps are sent as a client
of its own (``ros2-goal-<id>``): a cancel ends its running chunk between two steps, as a
native client's going does (issue 46: it used to run to the chunk's end, a million steps
for a 10^8-step goal). ``get_result`` is answered when its goal ends.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from galton.daemon.fronts.ros2 import codes
from galton.daemon.fronts.ros2.interfaces import ACTION, GOAL_STATUS_ARRAY
from galton.daemon.fronts.ros2.messages import new, time_msg
from galton.protocol import Reply

if TYPE_CHECKING:
    from galton.daemon.fronts.ros2.front import Ros2Front

# action_msgs/GoalStatus and CancelGoal codes
UNKNOWN, EXECUTING, CANCELING, SUCCEEDED, CANCELED, ABORTED = 0, 2, 3, 4, 5, 6
CANCEL_NONE, CANCEL_UNKNOWN_GOAL, CANCEL_TERMINATED = 0, 2, 3
FEEDBACK_CHUNKS = 100
KEPT_GOALS = 100  # finished goals remembered for get_result


@dataclass
class Goal:
    """One accepted goal and who waits for its result."""

    uuid: bytes
    steps: int
    accepted_at: float
    done: int = 0
    status: int = EXECUTING
    client: str = ""  # the native client id its steps are sent as
    result: tuple[int, str] = (codes.OK, "")
    waiting: list[Callable[[Any], None]] = field(default_factory=list)


class SimulateStepsServer:
    """The action server of one node."""

    def __init__(self, front: Ros2Front) -> None:
        self.front = front
        base = front.qualified(f"{front.identity.node}/simulate_steps/_action")
        self.feedback = front.publisher(f"{base}/feedback", f"{ACTION}_FeedbackMessage")
        self.status = front.publisher(f"{base}/status", GOAL_STATUS_ARRAY)
        self._lock = threading.Lock()
        self.goals: dict[bytes, Goal] = {}
        front.serve_raw(f"{base}/send_goal", f"{ACTION}_SendGoal", self._send_goal)
        front.serve_raw(f"{base}/get_result", f"{ACTION}_GetResult", self._get_result)
        front.serve_raw(f"{base}/cancel_goal", "action_msgs/srv/CancelGoal", self._cancel)

    def _send_goal(self, request: Any, answer: Callable[[Any], None]) -> None:
        """Accept a goal of at least one step (and a new goal id), record it before the
        answer leaves (a get_result may follow at once), then start it."""
        steps, uuid = int(request.goal.steps), bytes(request.goal_id.uuid)
        goal = Goal(uuid, steps, time.time(), client=f"ros2-goal-{uuid.hex()}")
        with self._lock:
            accepted = steps >= 1 and uuid not in self.goals
            if accepted:
                self.goals[uuid] = goal
                finished = [g for g in self.goals.values() if g.status >= SUCCEEDED]
                for old in finished[:-KEPT_GOALS]:
                    del self.goals[old.uuid]
        answer(new(f"{ACTION}_SendGoal_Response", accepted=accepted,
                   stamp=time_msg(goal.accepted_at)))
        if accepted:
            self._publish_status()
            self._next_chunk(goal)

    def _next_chunk(self, goal: Goal) -> None:
        chunk = min(goal.steps - goal.done, math.ceil(goal.steps / FEEDBACK_CHUNKS))
        with self._lock:  # a cancel's lose() comes after this chunk's call, or before it
            canceled = goal.status == CANCELING
            if not canceled:
                self.front.call("step", {"count": chunk},
                                lambda reply: self._stepped(goal, chunk, reply), goal.client)
        if canceled:
            self._finish(goal, CANCELED, (codes.OPERATION_FAILED, "canceled"))

    def _stepped(self, goal: Goal, chunk: int, reply: Reply) -> None:
        if not reply.ok:
            if goal.status == CANCELING:  # its chunk was ended by the cancel
                goal.done += int(reply.details.get("steps_done", 0))
                self._finish(goal, CANCELED, (codes.OPERATION_FAILED, "canceled"))
            else:
                self._finish(goal, ABORTED, (codes.OPERATION_FAILED, reply.message))
            return
        goal.done += chunk
        self.feedback.put(new(f"{ACTION}_FeedbackMessage", goal_id=_uuid(goal.uuid),
                              feedback=new(f"{ACTION}_Feedback", completed_steps=goal.done,
                                           remaining_steps=goal.steps - goal.done)))
        if goal.done == goal.steps:
            self._finish(goal, SUCCEEDED, (codes.OK, ""))
        else:
            self._next_chunk(goal)

    def _finish(self, goal: Goal, status: int, result: tuple[int, str]) -> None:
        with self._lock:
            goal.status, goal.result = status, result
            waiting, goal.waiting = goal.waiting, []
        self._publish_status()
        for answer in waiting:
            answer(self._result(goal))

    def _result(self, goal: Goal) -> Any:
        code, message = goal.result
        return new(f"{ACTION}_GetResult_Response", status=goal.status,
                   result=new(f"{ACTION}_Result", result=new(
                       "simulation_interfaces/msg/Result", result=code,
                       error_message=message)))

    def _get_result(self, request: Any, answer: Callable[[Any], None]) -> None:
        with self._lock:
            goal = self.goals.get(bytes(request.goal_id.uuid))
            if goal is not None and goal.status < SUCCEEDED:
                goal.waiting.append(answer)
                return
        answer(self._result(goal) if goal is not None else new(
            f"{ACTION}_GetResult_Response", status=UNKNOWN))

    def _cancel(self, request: Any, answer: Callable[[Any], None]) -> None:
        """Cancel one goal, or every running one when the goal id is all zeros."""
        wanted = bytes(request.goal_info.goal_id.uuid)
        with self._lock:
            chosen = [goal for goal in self.goals.values()
                      if wanted in (goal.uuid, bytes(16))]
            running = [goal for goal in chosen if goal.status == EXECUTING]
            for goal in running:
                goal.status = CANCELING
                self.front.lose(goal.client)  # its running or waiting chunk ends now
        code = (CANCEL_NONE if running else CANCEL_TERMINATED if chosen
                else CANCEL_UNKNOWN_GOAL)
        answer(new("action_msgs/srv/CancelGoal_Response", return_code=code,
                   goals_canceling=[self._info(goal) for goal in running]))
        if running:
            self._publish_status()

    def _info(self, goal: Goal) -> Any:
        return new("action_msgs/msg/GoalInfo", goal_id=_uuid(goal.uuid),
                   stamp=time_msg(goal.accepted_at))

    def _publish_status(self) -> None:
        with self._lock:
            goals = list(self.goals.values())
        self.status.put(new(GOAL_STATUS_ARRAY, status_list=[
            new("action_msgs/msg/GoalStatus", goal_info=self._info(goal), status=goal.status)
            for goal in goals]))


def _uuid(raw: bytes) -> Any:
    return new("unique_identifier_msgs/msg/UUID", uuid=np.frombuffer(raw, dtype=np.uint8))

