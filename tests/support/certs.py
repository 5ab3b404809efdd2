"""Self-made TLS certificates for the security tests, made with the ``openssl`` command.

Two certificate authorities: ``ca`` signs the daemon's certificate (for 127.0.0.1) and the
clients' (common names ``alice.robot`` and ``bob.view``); ``other-ca`` signs ``mallory``,
whose certificate claims alice's name. ECDSA P-256 keys: quick to make.
"""

from __future__ import annotations

import shutil
import subprocess
import zlib
from dataclasses import dataclass
from pathlib import Path

OPENSSL = shutil.which("openssl")
DAYS = "2"
CURVE = ["-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes"]


@dataclass(frozen=True)
class Pair:
    cert: Path
    key: Path


@dataclass(frozen=True)
class Certificates:
    ca: Path
    other_ca: Path
    daemon: Pair
    alice: Pair  # operator's certificate, signed by ca
    bob: Pair  # viewer's certificate, signed by ca
    mallory: Pair  # alice's name, signed by other_ca


def _openssl(*args: str) -> None:
    assert OPENSSL is not None
    subprocess.run([OPENSSL, *args], check=True, capture_output=True, timeout=30)


def _authority(folder: Path, name: str) -> Pair:
    pair = Pair(folder / f"{name}.pem", folder / f"{name}.key")
    _openssl("req", "-x509", *CURVE, "-keyout", str(pair.key), "-out", str(pair.cert),
             "-days", DAYS, "-subj", f"/CN={name}",
             "-addext", "basicConstraints=critical,CA:TRUE",
             "-addext", "keyUsage=critical,keyCertSign,cRLSign")
    return pair


def _leaf(folder: Path, name: str, authority: Pair, common_name: str,
          extensions: str) -> Pair:
    pair = Pair(folder / f"{name}.pem", folder / f"{name}.key")
    request, extfile = folder / f"{name}.csr", folder / f"{name}.ext"
    extfile.write_text(extensions)
    _openssl("req", *CURVE, "-keyout", str(pair.key), "-out", str(request),
             "-subj", f"/CN={common_name}")
    _openssl("x509", "-req", "-in", str(request), "-CA", str(authority.cert),
             "-CAkey", str(authority.key), "-set_serial", str(zlib.crc32(name.encode()) + 1),
             "-out", str(pair.cert), "-days", DAYS, "-extfile", str(extfile))
    return pair


def _client(folder: Path, name: str, authority: Pair, common_name: str) -> Pair:
    return _leaf(folder, name, authority, common_name,
                 f"extendedKeyUsage=clientAuth\nsubjectAltName=DNS:{common_name}\n")


def make_certificates(folder: Path) -> Certificates:
    """Every certificate the tests use, in ``folder``; skips the test without openssl
    (benchmarks/secure_latency.py uses it too, hence pytest imported only here)."""
    if OPENSSL is None:
        import pytest
        pytest.skip("the openssl command is not installed (nor is the cryptography package)")
    ca, other = _authority(folder, "ca"), _authority(folder, "other-ca")
    daemon = _leaf(folder, "daemon", ca, "localhost",
                   "subjectAltName=IP:127.0.0.1,DNS:localhost\nextendedKeyUsage=serverAuth\n")
    return Certificates(ca.cert, other.cert, daemon, _client(folder, "alice", ca, "alice.robot"),
                        _client(folder, "bob", ca, "bob.view"),
                        _client(folder, "mallory", other, "alice.robot"))
