"""Who a client is to a daemon started with ``--users`` or ``--tls-*`` (docs/SECURITY.md).

A password is never echoed: it is kept out of ``repr``, out of every error message, and
reaches Zenoh only as the salted hash the daemon's users file holds
(``galton.protocol.auth``). Sources, the later winning field by field: a credentials file
(``GALTON_CREDENTIALS``), the environment (``GALTON_USER``, ``GALTON_PASSWORD``), then the
command line (``--user``, ``--password-file``, ``--tls-ca``, ``--tls-cert``, ``--tls-key``).
The environment is read only where a caller hands it over (``from_env``).

A credentials file is TOML; relative paths are taken from the file's folder::

    user = "alice"
    password_file = "alice.password"   # or password = "..." or password_sha256 = "..."
    tls_ca = "ca.pem"                  # the CA that signed the daemon's certificate
    tls_cert = "alice.pem"             # for mutual TLS: this client's certificate
    tls_key = "alice.key"              # ... and its private key
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from galton.protocol.auth import is_wire_hash, validate_user_name, wire_password
from galton.protocol.errors import InvalidArgumentError, did_you_mean

USER_ENV = "GALTON_USER"
PASSWORD_ENV = "GALTON_PASSWORD"
FILE_ENV = "GALTON_CREDENTIALS"
FILE_FIELDS = ("user", "password", "password_file", "password_sha256", "tls_ca", "tls_cert",
               "tls_key")
TLS = "transport/link/tls/"
PEM_MARK = b"-----BEGIN "


@dataclass(frozen=True)
class Credentials:
    """A user and password, TLS files, or both. ``password`` is the clear password;
    ``password_sha256`` the wire hash instead (as a daemon's users file takes it)."""

    user: str | None = None
    password: str | None = field(default=None, repr=False)
    password_sha256: str | None = field(default=None, repr=False)
    tls_ca: Path | None = None
    tls_cert: Path | None = None
    tls_key: Path | None = None

    def __post_init__(self) -> None:
        self._check_password()
        if (self.tls_cert is None) != (self.tls_key is None):
            raise InvalidArgumentError("a TLS client certificate and its key go together: "
                                       "give both tls_cert and tls_key")
        for what, path in (("tls_ca", self.tls_ca), ("tls_cert", self.tls_cert),
                           ("tls_key", self.tls_key)):
            if path is not None:
                _check_pem(what, Path(path))

    def _check_password(self) -> None:
        has_password = self.password is not None or self.password_sha256 is not None
        if self.user is None:
            if has_password:
                raise InvalidArgumentError(
                    f"a password was given without a user: give the user too (--user or "
                    f"{USER_ENV})")
            return
        validate_user_name(self.user)
        if self.password is not None and self.password_sha256 is not None:
            raise InvalidArgumentError("give a password or its sha256, not both")
        if not has_password:
            raise InvalidArgumentError(
                f"user {self.user!r} was given without a password: use --password-file, "
                f"{PASSWORD_ENV} or a credentials file ({FILE_ENV})")
        if self.password == "":
            raise InvalidArgumentError(f"the password of user {self.user!r} is empty")
        if self.password_sha256 is not None and not is_wire_hash(self.password_sha256):
            raise InvalidArgumentError(
                f"the password_sha256 of user {self.user!r} must be 64 hex digits")

    @property
    def wire_password(self) -> str | None:
        """What Zenoh's usrpwd check compares (password-equivalent: never log it)."""
        if self.user is None:
            return None
        if self.password_sha256 is not None:
            return self.password_sha256.lower()
        return wire_password(self.user, str(self.password))

    @property
    def uses_tls(self) -> bool:
        return self.tls_ca is not None or self.tls_cert is not None

    def zenoh_settings(self) -> dict[str, Any]:
        """The Zenoh config values of these credentials, key path to value."""
        settings: dict[str, Any] = {}
        if self.user is not None:
            settings["transport/auth/usrpwd/user"] = self.user
            settings["transport/auth/usrpwd/password"] = self.wire_password
        if self.tls_ca is not None:
            settings[TLS + "root_ca_certificate"] = str(Path(self.tls_ca).resolve())
        if self.tls_cert is not None and self.tls_key is not None:
            settings[TLS + "connect_certificate"] = str(Path(self.tls_cert).resolve())
            settings[TLS + "connect_private_key"] = str(Path(self.tls_key).resolve())
            settings[TLS + "enable_mtls"] = True  # else Zenoh shows no certificate
        return settings

    def describe(self) -> str:
        """Who these credentials say this client is, without any secret."""
        parts = [f"user {self.user!r}"] if self.user is not None else ["no user"]
        if self.tls_cert is not None:
            parts.append(f"certificate {str(self.tls_cert)!r}")
        return ", ".join(parts)

    @classmethod
    def from_file(cls, path: Path | str) -> Credentials:
        """Credentials from a TOML credentials file (see the module's docstring)."""
        return cls(**read_credentials_file(Path(path)))

    @classmethod
    def from_env(cls, environ: Mapping[str, str]) -> Credentials | None:
        """Credentials from ``GALTON_CREDENTIALS``, then ``GALTON_USER`` and
        ``GALTON_PASSWORD``; None when none of them is set."""
        return resolve_credentials(environ=environ)


def _check_pem(what: str, path: Path) -> None:
    """Zenoh reads PEM only, and a TLS file it cannot parse fails ``zenoh.open`` just as a
    refused handshake does: without this check the SDK blamed the daemon."""
    try:
        data = path.read_bytes() if path.is_file() else None
    except OSError:
        data = None
    if data is None:
        raise InvalidArgumentError(f"{what} {str(path)!r} is not a readable file")
    if PEM_MARK not in data:
        raise InvalidArgumentError(
            f"{what} {str(path)!r} is not a PEM file (no {PEM_MARK.decode()!r} line): Zenoh "
            "takes certificates and keys in PEM (`openssl x509 -inform der -in X -out "
            "X.pem` converts a certificate)")


def read_password_file(path: Path | str) -> str:
    """The first line of a password file (its line break dropped)."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as error:
        raise InvalidArgumentError(
            f"cannot read the password file {str(path)!r}: {error.strerror}") from error
    lines = text.splitlines()
    if not lines or not lines[0]:
        raise InvalidArgumentError(f"the password file {str(path)!r} is empty")
    return lines[0]


def read_credentials_file(path: Path) -> dict[str, Any]:
    """A credentials file's fields as Credentials keywords (paths made absolute)."""
    try:
        with path.open("rb") as stream:
            document = tomllib.load(stream)
    except OSError as error:
        raise InvalidArgumentError(
            f"cannot read the credentials file {str(path)!r}: {error.strerror}") from error
    except tomllib.TOMLDecodeError as error:
        raise InvalidArgumentError(
            f"the credentials file {str(path)!r} is not TOML: {error}") from error
    for key in document:
        if key not in FILE_FIELDS:
            raise InvalidArgumentError(
                f"the credentials file {str(path)!r}: unknown field {key!r}"
                f"{did_you_mean(key, FILE_FIELDS)}; fields are {', '.join(FILE_FIELDS)}")
        if not isinstance(document[key], str):
            raise InvalidArgumentError(
                f"the credentials file {str(path)!r}: {key} must be a string")
    fields: dict[str, Any] = dict(document)
    for key in ("password_file", "tls_ca", "tls_cert", "tls_key"):
        if key in fields:
            fields[key] = path.parent / Path(fields[key]).expanduser()
    if "password_file" in fields:
        fields["password"] = read_password_file(fields.pop("password_file"))
    return fields


def resolve_credentials(user: str | None = None, password_file: Path | None = None,
                        tls_ca: Path | None = None, tls_cert: Path | None = None,
                        tls_key: Path | None = None,
                        environ: Mapping[str, str] | None = None) -> Credentials | None:
    """The credentials the command line and ``environ`` give, later sources winning field
    by field (file, environment, options); None when nothing is given."""
    env = environ or {}
    fields: dict[str, Any] = {}
    if env.get(FILE_ENV):
        fields.update(read_credentials_file(Path(env[FILE_ENV])))
    overrides: dict[str, Any] = {
        "user": user or env.get(USER_ENV) or None,
        "password": (read_password_file(password_file) if password_file is not None
                     else env.get(PASSWORD_ENV) or None),
        "tls_ca": tls_ca, "tls_cert": tls_cert, "tls_key": tls_key,
    }
    if overrides["password"] is not None:
        fields.pop("password_sha256", None)
    fields.update({key: value for key, value in overrides.items() if value is not None})
    return Credentials(**fields) if fields else None

