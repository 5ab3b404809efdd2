"""The fuzz harness: a seeded campaign against a daemon (``campaign.py``), its requests
generated from the operations' declarations (``requests.py``) and re-sealed corrupt
snapshots (``snapshots.py``)."""
