"""A do-nothing ZeroMQ ROUTER in its own process: the floor a ZeroMQ control call is held to.

Binds the endpoint given, answers every message at once with its routing frames and a small
fixed msgpack reply (as the daemon frames its replies), prints "ready" and serves until
stdin closes.
"""

from __future__ import annotations

import os
import sys
import threading

import msgpack
import zmq

REPLY = msgpack.packb({"v": 1, "code": 0, "code_name": "OK", "message": "", "result": {},
                       "step": 0, "sim_time": 0.0, "details": {}})


def main(endpoint: str) -> None:
    context = zmq.Context()
    router = context.socket(zmq.ROUTER)
    router.bind(endpoint)

    def serve() -> None:
        while True:
            frames = router.recv_multipart()
            router.send_multipart([*frames[:-1], REPLY])
    threading.Thread(target=serve, daemon=True).start()
    print("ready", flush=True)
    sys.stdin.read()
    os._exit(0)  # the serving thread holds the socket: no clean close from here


if __name__ == "__main__":
    main(sys.argv[1])
