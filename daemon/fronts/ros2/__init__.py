"""The ROS 2 front (``galton-daemon --ros2``): simulation_interfaces services, /clock, /tf
and joint mirroring in rmw_zenoh's wire format on the daemon's Zenoh session; needs the
``[ros2]`` extra (rosbags), so nothing here is imported before the front starts (the
options module excepted). docs/ROS2.md says what maps to what.

Modules: ``options`` (what the command line gives), ``rmw_zenoh`` (keys, attachments,
tokens), ``interfaces`` (simulation_interfaces types and RIHS01 hashes), ``messages``
(CDR), ``native`` / ``services`` / ``spawning`` (services onto operations), ``topics``
(/clock, /tf, mirrors), ``front`` (the node)."""
