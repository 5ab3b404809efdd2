"""The users file of ``galton-daemon --users`` and the Zenoh access control made from it:
every bad entry is refused by user and field, secrets never show, rules stay one-way."""

from __future__ import annotations

import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from galton.daemon.access.users import ROLES, load_users, parse_users, readable_by_others
from galton.daemon.access.zenoh_security import (
    ROLE_RULES,
    TlsFiles,
    access_control,
    acl_rules,
    check_reachable,
    dictionary_text,
    security_settings,
    write_private_file,
)
from galton.protocol.auth import wire_password
from galton.protocol.errors import InvalidArgumentError

KEY = "rq:rM>}U?@Lns47E1%kR.o@n%FcmmsL/@{H8]yf7"  # a Z85 CURVE public key (40 characters)
GOOD = f"""
[users.alice]
role = "operator"
password = "correct horse"
tls_name = "alice.robot"
zmq_public_key = "{KEY}"

[users.bob]
role = "viewer"
password_sha256 = "{"AB" * 32}"
"""


def users_from(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "users.toml"
    path.write_text(text)
    return path


def test_a_good_file_gives_each_user_its_role_and_wire_secret(tmp_path: Path) -> None:
    users = load_users(users_from(tmp_path, GOOD))
    alice, bob = users["alice"], users["bob"]
    assert (alice.role, alice.tls_name, alice.zmq_public_key) == ("operator", "alice.robot", KEY)
    assert alice.secret == wire_password("alice", "correct horse")
    assert (bob.role, bob.secret, bob.tls_name) == ("viewer", "ab" * 32, None)
    assert alice.operator and not bob.operator


def test_a_users_repr_never_shows_its_secret(tmp_path: Path) -> None:
    users = load_users(users_from(tmp_path, GOOD))
    shown = repr(users)
    assert "correct horse" not in shown
    assert str(users["alice"].secret) not in shown and "ab" * 32 not in shown


@pytest.mark.parametrize(("entry", "expected"), [
    ('role = "admin"\npassword = "x"',
     r"user 'carol': role 'admin' is not one of operator, viewer"),
    ('role = "operater"\npassword = "x"', r"did you mean 'operator'"),
    ('password = "x"', r"user 'carol': role None"),
    ('role = "viewer"', r"user 'carol' has no password"),
    ('role = "viewer"\npassword = ""', r"user 'carol': password must be a non-empty string"),
    ('role = "viewer"\npassword = "x"\npassword_sha256 = "' + "a" * 64 + '"',
     r"user 'carol': give password or password_sha256, not both"),
    ('role = "viewer"\npassword_sha256 = "abc"', r"user 'carol': password_sha256 must be 64 hex"),
    ('role = "viewer"\npasword = "x"', r"user 'carol': unknown field 'pasword'.*'password'"),
    ('role = "viewer"\npassword = "x"\nzmq_public_key = "short"',
     r"user 'carol': zmq_public_key must be .* 40 characters.*got 5 characters"),
    ('role = "viewer"\npassword = "x"\nzmq_public_key = "' + "~" * 40 + '"',
     r"user 'carol': zmq_public_key .* not Z85"),
    ('role = "viewer"\npassword = "x"\ntls_name = ""', r"user 'carol': tls_name must be"),
])
def test_a_bad_entry_is_refused_by_user_and_field(tmp_path: Path, entry: str,
                                                  expected: str) -> None:
    with pytest.raises(InvalidArgumentError, match=expected) as caught:
        load_users(users_from(tmp_path, f"[users.carol]\n{entry}\n"))
    # the password "x" as a message would quote it ({!r} and brief() use single quotes)
    assert "'x'" not in str(caught.value) and '"x"' not in str(caught.value)


def test_a_password_is_never_quoted_in_an_error(tmp_path: Path) -> None:
    with pytest.raises(InvalidArgumentError) as caught:
        load_users(users_from(tmp_path, '[users.carol]\nrole = "boss"\npassword = "hunter2"\n'))
    assert "hunter2" not in str(caught.value)


@pytest.mark.parametrize(("text", "expected"), [
    ("", r"names no users"),
    ("[users]\n", r"names no users"),
    ('[groups.a]\nrole = "viewer"\n', r"unknown top-level key 'groups'"),
    ('[users."bad:name"]\nrole = "viewer"\npassword = "x"\n', r"user name 'bad:name' is not valid"),
    ("[users.alice\n", r"is not TOML"),
    ('[users.a]\nrole = "viewer"\npassword = "x"\ntls_name = "same"\n'
     '[users.b]\nrole = "operator"\npassword = "y"\ntls_name = "same"\n',
     r"user 'b' has the same tls_name as user 'a'"),
    (f'[users.a]\nrole = "viewer"\nzmq_public_key = "{KEY}"\n'
     f'[users.b]\nrole = "viewer"\nzmq_public_key = "{KEY}"\n',
     r"user 'b' has the same zmq_public_key as user 'a'"),
])
def test_a_bad_file_is_refused(tmp_path: Path, text: str, expected: str) -> None:
    with pytest.raises(InvalidArgumentError, match=expected):
        load_users(users_from(tmp_path, text))


@pytest.mark.parametrize(("entry", "expected"), [
    ({"alice\n": {"role": "viewer", "password": "x"}}, r"user name 'alice\\n' is not valid"),
    ({"alice": {"role": "viewer", "password_sha256": "ab" * 32 + "\n"}},
     r"user 'alice': password_sha256 must be 64 hex digits"),
])
def test_a_trailing_line_break_is_refused(entry: dict[str, object], expected: str) -> None:
    """A name or hash ending in a line break used to pass (``$`` matches before it): the
    name split Zenoh's dictionary line and the daemon failed with Zenoh's own message."""
    with pytest.raises(InvalidArgumentError, match=expected):
        parse_users({"users": entry})


def test_a_missing_file_is_refused_by_path(tmp_path: Path) -> None:
    with pytest.raises(InvalidArgumentError, match=r"cannot read the users file .*nowhere"):
        load_users(tmp_path / "nowhere.toml")


# -- the Zenoh side -----------------------------------------------------------------------
def test_every_rule_goes_one_way_and_nobody_may_publish_or_answer_inbound() -> None:
    rules = acl_rules("robot")
    assert all(len(rule["flows"]) == 1 for rule in rules)
    inbound = {m for rule in rules if rule["flows"] == ["ingress"] for m in rule["messages"]}
    assert inbound.isdisjoint({"put", "delete", "reply", "declare_queryable"})
    by_id = {rule["id"]: rule for rule in rules}
    assert set(ROLE_RULES) == set(ROLES)
    assert all(rule_id in by_id for ids in ROLE_RULES.values() for rule_id in ids)


def test_a_viewer_may_ask_only_read_only_operations() -> None:
    by_id = {rule["id"]: rule for rule in acl_rules("robot")}
    asked = {key for rule_id in ROLE_RULES["viewer"] for key in by_id[rule_id]["key_exprs"]
             if "query" in by_id[rule_id]["messages"] and by_id[rule_id]["flows"] == ["ingress"]}
    assert asked == {f"galton/robot/@ctl/{op}" for op in (
        "status", "capabilities", "list", "list_worlds", "contacts", "stream_states",
        "close_stream", "get_shapes")}
    assert "client-token" not in ROLE_RULES["viewer"]
    assert by_id["viewer-token"]["key_exprs"] == ["galton/_clients/viewer-$*"]


def test_subjects_by_certificate_only_with_mutual_tls() -> None:
    users = parse_users({"users": {
        "alice": {"role": "operator", "password": "a", "tls_name": "alice.robot"},
        "bob": {"role": "viewer", "tls_name": "bob.view"}}})
    plain = access_control(users, "robot")
    assert plain["default_permission"] == "deny"
    assert plain["subjects"] == [{"id": "operator-users", "usernames": ["alice"]}]
    assert [p["id"] for p in plain["policies"]] == ["operator"]
    mutual = access_control(users, "robot", by_certificate=True)
    assert {"id": "viewer-certificates", "cert_common_names": ["bob.view"]} in mutual["subjects"]
    with pytest.raises(InvalidArgumentError, match="user 'bob' has a tls_name but no password"):
        check_reachable(users, by_certificate=True)


def test_the_dictionary_holds_wire_secrets_in_a_private_file() -> None:
    users = parse_users({"users": {"alice": {"role": "operator", "password": "a"},
                                   "bob": {"role": "viewer", "tls_name": "bob.view"}}})
    text = dictionary_text(users)
    assert text == f"alice:{wire_password('alice', 'a')}\n"
    path = write_private_file(text)
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    assert path.read_text() == text
    settings = security_settings(users, None, "robot")
    assert Path(settings["transport/auth/usrpwd/dictionary_file"]).read_text() == text


def test_the_private_file_is_removed_when_the_process_exits() -> None:
    code = ("from galton.daemon.access.zenoh_security import write_private_file; "
            "print(write_private_file('alice:x\\n'))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True, timeout=60)
    assert not os.path.exists(done.stdout.strip())


def test_tls_files_must_exist(tmp_path: Path) -> None:
    with pytest.raises(InvalidArgumentError, match=r"--tls-cert .* is not a readable file"):
        TlsFiles(tmp_path / "no.pem", tmp_path / "no.key")


def test_a_users_file_others_can_read_is_noticed(tmp_path: Path) -> None:
    path = users_from(tmp_path, GOOD)
    path.chmod(0o600)
    assert not readable_by_others(path)
    path.chmod(0o644)
    assert readable_by_others(path)
