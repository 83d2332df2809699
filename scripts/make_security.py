#!/usr/bin/env python3
"""Makes a demo DDS Security setup for surfeledit (proto/PROTOCOL.md, "Security"): two CAs, one
identity per named user, a signed governance document and one signed permissions document per user.

    python3 scripts/make_security.py OUT [--server server] [--clients alice,bob] [--denied mallory]
                                         [--rogue eve] [--days 365] [--domains 0-230]

Needs only the `openssl` command (Debian package openssl). Everything is written below OUT:

    OUT/ca/identity_ca.pem  identity_ca.key      signs the users' certificates (authentication)
    OUT/ca/permissions_ca.pem  permissions_ca.key   signs governance and permissions (S/MIME)
    OUT/governance.xml  governance.p7s           the domain rule: no unauthenticated participants,
                                                 discovery, liveliness and every topic encrypted,
                                                 read and write access control on every topic
    OUT/<user>/cert.pem  key.pem                 the user's identity (subject CN=<user>,O=surfeledit)
    OUT/<user>/permissions.xml  permissions.p7s  what the user may publish and subscribe
    OUT/<user>/security.conf                     the file to give `surfeledit-server --security` or a client

Users: `--server` may read requests and write replies and updates; each of `--clients` may write
requests only in the default partition and its own "surfeledit.req.<user>" (which the server reads as
the authenticated user, for --grant), read updates, and read replies only in its own reply partitions "surfeledit.reply.<user>.*"
(so its client ids must start with "<user>.": the Python client does that with `user` of its
security.conf); each of `--denied` has a valid identity and permissions that
allow the domain but none of surfeledit's topics; each of `--rogue` has a valid identity but
permissions (and governance) signed by a CA of its own, which grant everything (an attacker who
signs its own permissions). The private keys are unencrypted: a demo, not a deployment.
"""

from __future__ import annotations

import argparse
import datetime as dt
import subprocess
import sys
from pathlib import Path
from typing import List, Sequence, Tuple

TOPICS_SERVER_PUBLISHES = ("surfeledit_reply", "surfeledit_update")
TOPICS_SERVER_SUBSCRIBES = ("surfeledit_request", "surfeledit_reply")  # replies: the one-server-per-domain probe
TOPICS_CLIENT_PUBLISHES = ("surfeledit_request",)
TOPICS_CLIENT_SUBSCRIBES = ("surfeledit_reply", "surfeledit_update")
ORGANISATION = "surfeledit"


def subject(user: str) -> str:
    """The certificate subject of `user`, as permissions documents name it."""
    return f"CN={user},O={ORGANISATION}"


def openssl(*args: str, cwd: Path) -> None:
    r = subprocess.run(["openssl", *args], cwd=cwd, capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"openssl {' '.join(args)} failed:\n{r.stderr}")


def make_key(path: Path) -> None:
    """An EC P-256 private key (one of the two key types Cyclone's authentication plugin accepts)."""
    openssl("ecparam", "-name", "prime256v1", "-genkey", "-noout", "-out", path.name, cwd=path.parent)


def make_ca(directory: Path, name: str, common_name: str, days: int) -> Tuple[Path, Path]:
    key, cert = directory / f"{name}.key", directory / f"{name}.pem"
    make_key(key)
    openssl("req", "-new", "-x509", "-sha256", "-key", key.name, "-out", cert.name, "-days", str(days),
            "-subj", f"/CN={common_name}/O={ORGANISATION}", cwd=directory)
    return cert, key


def make_identity(directory: Path, user: str, ca_cert: Path, ca_key: Path, days: int) -> None:
    make_key(directory / "key.pem")
    openssl("req", "-new", "-sha256", "-key", "key.pem", "-out", "cert.csr",
            "-subj", f"/CN={user}/O={ORGANISATION}", cwd=directory)
    openssl("x509", "-req", "-sha256", "-in", "cert.csr", "-CA", str(ca_cert), "-CAkey", str(ca_key),
            "-CAcreateserial", "-out", "cert.pem", "-days", str(days), cwd=directory)
    (directory / "cert.csr").unlink()


def sign(document: Path, ca_cert: Path, ca_key: Path) -> Path:
    """S/MIME signs `document` (clear text) with the permissions CA; returns the .p7s path."""
    out = document.with_suffix(".p7s")
    openssl("smime", "-sign", "-text", "-in", document.name, "-out", out.name, "-signer", str(ca_cert),
            "-inkey", str(ca_key), cwd=document.parent)
    return out


def domains_xml(domains: Tuple[int, int], indent: str) -> str:
    return (f"{indent}<domains><id_range><min>{domains[0]}</min><max>{domains[1]}</max></id_range></domains>\n")


def governance_xml(domains: Tuple[int, int]) -> str:
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        "<dds>\n"
        "  <domain_access_rules>\n"
        "    <domain_rule>\n"
        + domains_xml(domains, "      ")
        + "      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>\n"
        "      <enable_join_access_control>true</enable_join_access_control>\n"
        "      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>\n"
        "      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>\n"
        "      <rtps_protection_kind>NONE</rtps_protection_kind>\n"
        "      <topic_access_rules>\n"
        "        <topic_rule>\n"
        "          <topic_expression>*</topic_expression>\n"
        "          <enable_discovery_protection>true</enable_discovery_protection>\n"
        "          <enable_liveliness_protection>true</enable_liveliness_protection>\n"
        "          <enable_read_access_control>true</enable_read_access_control>\n"
        "          <enable_write_access_control>true</enable_write_access_control>\n"
        "          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>\n"
        "          <data_protection_kind>ENCRYPT</data_protection_kind>\n"
        "        </topic_rule>\n"
        "      </topic_access_rules>\n"
        "    </domain_rule>\n"
        "  </domain_access_rules>\n"
        "</dds>\n")


def reply_partitions(user: str) -> str:
    """The partitions a client user may read replies in: those of its own client ids, which start
    with "<user>." (the client's reply partition is "surfeledit.reply.<client id>"; user names have
    no ".", so no user's pattern matches another's partitions)."""
    return f"surfeledit.reply.{user}.*"


def request_partitions(user: str) -> List[str]:
    """The partitions a client user may write requests in: its own "surfeledit.req.<user>" (which
    therefore names the authenticated user to the server: its --grant roles apply there) and the
    default partition (requests the server cannot attribute to a user: no granted role)."""
    return ["", f"surfeledit.req.{user}"]


def criteria_xml(kind: str, topics: Sequence[str], partitions: Sequence[str] = ("*",)) -> str:
    """A publish or subscribe criterion over `topics` in the partitions matching one of `partitions`
    ("*": every partition, the default one included; the per-client reply partitions are made at run time)."""
    names = "".join(f"<topic>{t}</topic>" for t in topics)
    parts = "".join(f"<partition>{p}</partition>" for p in partitions)
    return (f"        <{kind}>\n          <topics>{names}</topics>\n"
            f"          <partitions>{parts}</partitions>\n        </{kind}>\n")


def permissions_xml(user: str, publish: Sequence[str], subscribe: Sequence[str], domains: Tuple[int, int],
                    days: int, own_replies: bool = False) -> str:
    """`own_replies` (client users): surfeledit_reply (in `subscribe`) only in the user's own reply
    partitions, surfeledit_request (in `publish`) only in its request partitions."""
    now = dt.datetime.now(dt.timezone.utc).replace(microsecond=0, tzinfo=None)
    not_before = (now - dt.timedelta(days=1)).isoformat()
    not_after = (now + dt.timedelta(days=days)).isoformat()
    rules = ""
    if own_replies and "surfeledit_request" in publish:
        rules += criteria_xml("publish", ["surfeledit_request"], request_partitions(user))
        publish = [t for t in publish if t != "surfeledit_request"]
    if publish:
        rules += criteria_xml("publish", publish)
    if own_replies and "surfeledit_reply" in subscribe:
        rules += criteria_xml("subscribe", ["surfeledit_reply"], [reply_partitions(user)])
        subscribe = [t for t in subscribe if t != "surfeledit_reply"]
    if subscribe:
        rules += criteria_xml("subscribe", subscribe)
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        "<dds>\n"
        "  <permissions>\n"
        f'    <grant name="{user}">\n'
        f"      <subject_name>{subject(user)}</subject_name>\n"
        f"      <validity><not_before>{not_before}</not_before><not_after>{not_after}</not_after></validity>\n"
        "      <allow_rule>\n"
        + domains_xml(domains, "        ")
        + rules
        + "      </allow_rule>\n"
        "      <default>DENY</default>\n"
        "    </grant>\n"
        "  </permissions>\n"
        "</dds>\n")


def write_conf(directory: Path, user: str, identity_ca: Path, permissions_ca: Path, governance: Path) -> None:
    rel = lambda p: Path(p).resolve().relative_to(directory.parent.resolve())  # noqa: E731
    (directory / "security.conf").write_text(
        "# DDS Security files of one participant (surfeledit-server --security, or a client's option).\n"
        "# Relative paths are relative to this file. Written by scripts/make_security.py.\n"
        f"identity_ca = ../{rel(identity_ca)}\n"
        "identity_certificate = cert.pem\n"
        "private_key = key.pem\n"
        f"permissions_ca = ../{rel(permissions_ca)}\n"
        f"governance = ../{rel(governance)}\n"
        "permissions = permissions.p7s\n"
        "# The certificate's CN: a client's ids start with '<user>.' (its reply partitions).\n"
        f"user = {user}\n")


def parse_names(text: str) -> List[str]:
    names = [n.strip() for n in text.split(",") if n.strip()]
    for n in names:
        if not n.replace("-", "").replace("_", "").isalnum() or n in ("ca", "rogue-ca"):
            raise SystemExit(f"bad user name {n!r}: letters, digits, - and _ only; not 'ca'")
    return names


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--server", default="server", help="the server's user name")
    ap.add_argument("--clients", default="alice,bob", help="comma-separated permitted client users")
    ap.add_argument("--denied", default="mallory", help="users with an identity but no surfeledit permission")
    ap.add_argument("--rogue", default="eve", help="users whose permissions are signed by their own CA")
    ap.add_argument("--days", type=int, default=365, help="validity of certificates and permissions")
    ap.add_argument("--domains", default="0-230", help="DDS domain id range MIN-MAX the documents cover")
    a = ap.parse_args(argv)
    lo, _, hi = a.domains.partition("-")
    domains = (int(lo), int(hi or lo))
    if not (0 <= domains[0] <= domains[1] <= 230):
        raise SystemExit("--domains must be MIN-MAX within 0-230 (the documents' limit)")
    clients, denied, rogue = parse_names(a.clients), parse_names(a.denied), parse_names(a.rogue)
    users = parse_names(a.server) + clients + denied + rogue
    if len(set(users)) != len(users):
        raise SystemExit("user names must be distinct")

    out = a.out.resolve()
    ca_dir = out / "ca"
    ca_dir.mkdir(parents=True, exist_ok=True)
    id_ca, id_key = make_ca(ca_dir, "identity_ca", "surfeledit identity CA", a.days)
    perm_ca, perm_key = make_ca(ca_dir, "permissions_ca", "surfeledit permissions CA", a.days)
    governance = out / "governance.xml"
    governance.write_text(governance_xml(domains))
    governance_p7s = sign(governance, perm_ca, perm_key)

    def user(name: str, publish: Sequence[str], subscribe: Sequence[str], ca: Tuple[Path, Path], gov: Path,
             own_replies: bool = False) -> None:
        d = out / name
        d.mkdir(exist_ok=True)
        make_identity(d, name, id_ca, id_key, a.days)
        perms = d / "permissions.xml"
        perms.write_text(permissions_xml(name, publish, subscribe, domains, a.days, own_replies))
        sign(perms, *ca)
        write_conf(d, name, id_ca, ca[0], gov)

    user(a.server, TOPICS_SERVER_PUBLISHES, TOPICS_SERVER_SUBSCRIBES, (perm_ca, perm_key), governance_p7s)
    for name in clients:
        user(name, TOPICS_CLIENT_PUBLISHES, TOPICS_CLIENT_SUBSCRIBES, (perm_ca, perm_key), governance_p7s,
             own_replies=True)
    for name in denied:  # the domain only: a participant, but no endpoint on any surfeledit topic
        user(name, ("surfeledit_none",), (), (perm_ca, perm_key), governance_p7s)
    if rogue:
        rogue_dir = out / "rogue-ca"
        rogue_dir.mkdir(exist_ok=True)
        rca = make_ca(rogue_dir, "permissions_ca", "rogue permissions CA", a.days)
        rgov = rogue_dir / "governance.xml"
        rgov.write_text(governance_xml(domains))
        rgov_p7s = sign(rgov, *rca)
        everything = tuple(dict.fromkeys(TOPICS_SERVER_PUBLISHES + TOPICS_SERVER_SUBSCRIBES))
        for name in rogue:
            user(name, everything, everything, rca, rgov_p7s)
    print(f"security files for {', '.join(users)} in {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
