"""The ways requests come in and telemetry goes out: ZeroMQ (zmq.py), the Zenoh
configuration (zenoh_config.py; the Zenoh side itself is still daemon/server.py), ROS 2 (ros2/)."""
