"""A do-nothing Zenoh queryable in its own process: the floor a control call is held to.

Listens on the endpoint given, answers every query on ``null/@ctl/*`` at once with a
small fixed msgpack reply, prints "ready" and serves until stdin closes.
"""

from __future__ import annotations

import json
import sys

import msgpack
import zenoh

REPLY = msgpack.packb({"v": 1, "code": 0, "code_name": "OK", "message": "", "result": {},
                       "step": 0, "sim_time": 0.0, "details": {}})


def main(endpoint: str) -> None:
    config = zenoh.Config()
    config.insert_json5("mode", '"peer"')
    config.insert_json5("listen/endpoints", json.dumps([endpoint]))
    config.insert_json5("scouting/multicast/enabled", "false")
    with zenoh.open(config) as session:

        def answer(query: zenoh.Query) -> None:
            with query:
                query.reply(query.key_expr, REPLY)

        session.declare_queryable("null/@ctl/*", answer)
        print("ready", flush=True)
        sys.stdin.read()


if __name__ == "__main__":
    main(sys.argv[1])
