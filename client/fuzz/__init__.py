"""The fuzz harness: a seeded campaign against a daemon (``campaign.py``), its requests
generated from the operations' declarations (``requests.py``), re-sealed corrupt
snapshots (``snapshots.py``), requests whose replies would pass the reply limit
(``oversize.py``) and a ZeroMQ client that never reads its replies (``unread.py``)."""
