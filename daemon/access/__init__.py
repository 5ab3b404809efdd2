"""Who may do what: users and roles, the control lease, Zenoh ACL and TLS, ZeroMQ CURVE."""
