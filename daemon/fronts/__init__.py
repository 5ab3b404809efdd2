"""The ways requests come in and telemetry goes out, each a Front (base.py): Zenoh
(zenoh.py, its configuration rules in zenoh_config.py), ZeroMQ (zmq.py), ROS 2 (ros2/)."""
