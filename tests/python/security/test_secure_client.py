"""The Python client with DDS Security (``connect(security=...)``, PROTOCOL.md "Security") against a
real ``surfeledit-server --security`` on a unique domain: a permitted identity works end to end; an
identity without permission, one whose permissions a foreign CA signed and a user reading another
user's replies are refused with typed errors. Runs in ``.venv-secure`` (skipped elsewhere)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import surfeledit
from surfeledit.security import SecurityConfig, security_available

if not security_available():
    pytest.skip("this cyclonedds binding has no DDS Security plugins (run in .venv-secure)", allow_module_level=True)




def conf(security_dir: Path, user: str) -> Path:
    return security_dir / user / "security.conf"


def sphere(n: int, seed: int):
    """n points on the unit sphere with their outward normals, shifted up by 2 (clear of the slab)."""
    rng = np.random.default_rng(seed)
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    return p + (0.0, 0.0, 2.0), p.copy()


def slab(n_side: int):
    g = np.linspace(-1.5, 1.5, n_side)
    x, y = np.meshgrid(g, g)
    p = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    return p, np.tile((0.0, 0.0, 1.0), (len(p), 1))


def test_permitted_identity_opens_deforms_undoes_and_watches(secured_server, security_dir: Path) -> None:
    sp, sn = sphere(400, 1)
    bp, bn = slab(20)
    positions, normals = np.vstack([bp, sp]), np.vstack([bn, sn])
    zero, one = np.arange(len(bp)), np.arange(len(bp), len(positions))
    t = np.array([0.0, 0.0, -0.25])
    with surfeledit.connect(secured_server.domain, security=conf(security_dir, "alice"), timeout=15) as client:
        assert client.security is not None and client.security.user == "alice"
        assert client.client_id.startswith("alice.")
        with client.open_session("secured") as s, s.watch() as w:
            s.load_points(positions, normals)
            s.set_regions(zero=zero, one=one)
            before = s.positions().copy()
            np.testing.assert_array_equal(before, positions)  # the model is what was sent
            step = s.deform(translation=tuple(t))
            assert step.seq == 1 and step.version > 0
            moved = s.positions()
            # Independent truth: region one translated by t (no contact this far above the slab),
            # region zero where it was.
            np.testing.assert_allclose(moved[one], positions[one] + t, atol=1e-9)
            np.testing.assert_array_equal(moved[zero], positions[zero])
            s.undo()
            np.testing.assert_array_equal(s.positions(), positions)
            # The watcher saw the deform and the undo of this session, over the encrypted topic.
            causes = []
            while len(causes) < 4:
                ev = w.get(timeout=10)
                assert ev is not None, causes
                if ev.session == "secured":
                    causes.append(ev.cause)
                    if ev.cause == "undo":
                        break
            assert "deform" in causes and causes[-1] == "undo", causes
    assert secured_server.alive, secured_server.log_tail()


def test_identity_without_surfeledit_permission_is_refused(secured_server, security_dir: Path) -> None:
    with pytest.raises(surfeledit.AccessDeniedError) as e:
        surfeledit.connect(secured_server.domain, security=conf(security_dir, "mallory"), timeout=5)
    assert e.value.field in ("request topic", "request writer")
    assert "NOT_ALLOWED_BY_SECURITY" in str(e.value)
    assert secured_server.alive


def test_permissions_signed_by_a_foreign_ca_find_no_server(secured_server, security_dir: Path) -> None:
    """Eve's own CA signed her permissions: her participant exists locally, but the server does not
    authenticate it, so nothing of hers is matched and no server answers her."""
    with pytest.raises(surfeledit.ServerStartError, match="DDS Security"):
        surfeledit.connect(secured_server.domain, security=conf(security_dir, "eve"), timeout=3)
    assert secured_server.alive


def test_plain_client_sees_no_secured_server(secured_server) -> None:
    with pytest.raises(surfeledit.ServerStartError):
        surfeledit.connect(secured_server.domain, spawn=False, timeout=2)


def test_user_cannot_read_another_users_replies(secured_server, security_dir: Path) -> None:
    """Bob may read replies only in "surfeledit.reply.bob.*": in a process of his own, a client with
    one of alice's ids and raw readers of alice's reply partition (or of every reply partition) are
    refused, while a reader of his own partitions is created; alice, meanwhile, gets her replies."""
    with surfeledit.connect(secured_server.domain, security=conf(security_dir, "alice"), timeout=15) as alice:
        alice.info()
        r = subprocess.run([sys.executable, str(Path(__file__).with_name("reply_snoop.py")), str(conf(security_dir, "bob")),
                            str(secured_server.domain), alice.client_id], capture_output=True, text=True, timeout=60)
        out = dict(line.split("=", 1) for line in r.stdout.splitlines() if "=" in line)
        assert r.returncode == 0, r.stderr
        assert out["client"] == "AccessDeniedError:reply reader", out
        readers = {k: v for k, v in out.items() if k.startswith("reader:")}
        assert len(readers) == 4 and set(readers.values()) == {"refused"}, out
        assert out["own"] == "allowed", out  # the refusal is the partition's, not the topic's
        assert out["own_client"].startswith("bob:"), out  # bob's own client is served
        assert alice.info().version  # and alice still is


def test_bad_security_config_is_a_typed_error(tmp_path: Path, security_dir: Path) -> None:
    text = conf(security_dir, "alice").read_text()
    bad = tmp_path / "sub" / "alice.conf"  # relative paths now point nowhere
    bad.parent.mkdir()
    bad.write_text(text)
    with pytest.raises(surfeledit.SecurityConfigError) as e:
        surfeledit.connect(1, security=bad, timeout=1)
    assert e.value.field == "identity_ca"
    missing = conf(security_dir, "alice").parent / "missing-permissions.conf"  # relative paths resolve
    missing.write_text("\n".join(l for l in text.splitlines() if not l.startswith("permissions =")) + "\n")
    with pytest.raises(surfeledit.SecurityConfigError, match="missing key 'permissions'"):
        SecurityConfig.load(missing)


def test_one_identity_per_process(security_dir: Path) -> None:
    """A second identity in a process where a secured client is open is refused before any DDS entity
    is made (Cyclone 0.10.2 mixes the identities of one process up); the same identity is fine, and
    another one once the first client closed."""
    from surfeledit.connection import Client
    from surfeledit.dds_status import publication_matched

    with Client(1, security=conf(security_dir, "alice")) as a1, Client(1, security=conf(security_dir, "alice")) as a2:
        assert a1.client_id != a2.client_id and publication_matched(a1._writer) == 0
        with pytest.raises(surfeledit.SecurityConfigError) as e:
            Client(1, security=conf(security_dir, "bob"))
        assert e.value.field == "identity_certificate"
    with Client(1, security=conf(security_dir, "bob")) as b:
        assert b.client_id.startswith("bob.")


def test_roles_granted_to_authenticated_users(request, tmp_path: Path, security_dir: Path) -> None:
    """`--grant bob=editor:shared --grant carol=viewer`: bob (his requests come in "surfeledit.req.bob",
    which only his identity may write in) joins alice's private session "shared" without a token and
    edits it; carol joins and reads but her deform is refused; dave, authenticated but granted
    nothing, gets the same NotFound as for a session that does not exist; bob's grant names one session."""
    from service.conftest import SecuredServer

    srv = SecuredServer.started(request, tmp_path, security_dir / "server" / "security.conf",
                                ["--grant", "bob=editor:shared", "--grant", "carol=viewer"])

    def peer(user: str, session: str) -> dict:
        r = subprocess.run([sys.executable, str(Path(__file__).with_name("grant_peer.py")), str(conf(security_dir, user)),
                            str(srv.domain), session, str(len(bp))], capture_output=True, text=True, timeout=90)
        assert r.returncode == 0, r.stderr[-3000:]
        return dict(line.split("=", 1) for line in r.stdout.splitlines() if "=" in line)

    sp, sn = sphere(300, 2)
    bp, bn = slab(15)
    positions = np.vstack([bp, sp])
    with surfeledit.connect(srv.domain, security=conf(security_dir, "alice"), timeout=15) as alice, \
            alice.open_session("shared") as s, alice.open_session("private") as other:
        s.load_points(positions, np.vstack([bn, sn]))  # the tools (regions) are the peers'
        other.load_points(positions, np.vstack([bn, sn]))
        s.info()
        v0 = s.version

        bob = peer("bob", "shared")
        assert bob["join"] == "ok" and bob["surfels"] == str(len(positions)) and bob["regions"] == "ok", bob
        assert bob["deform"].startswith("ok:") and int(bob["version"]) > v0, bob
        # Independent truth: bob's step moved the sphere by (0, 0, -0.01) in alice's view too.
        np.testing.assert_allclose(s.positions()[len(bp):], sp + (0.0, 0.0, -0.01), atol=1e-9)
        s.info()
        v1, h1 = s.version, s.info().state_hash

        carol = peer("carol", "shared")
        assert carol["join"] == "ok" and carol["surfels"] == str(len(positions)), carol
        assert carol["regions"] == carol["deform"] == "PermissionDeniedError" and int(carol["version"]) == v1, carol

        assert peer("dave", "shared") == {"join": "NotFoundError"}
        assert peer("dave", "no-such-session") == {"join": "NotFoundError"}
        assert peer("bob", "private") == {"join": "NotFoundError"}  # his grant names "shared" only
        assert s.info().state_hash == h1 and s.version == v1 and other.info().surfels == len(positions)
    assert "is user 'bob'" in srv.log_tail(200_000) and srv.alive


def test_grant_needs_security(tmp_path: Path) -> None:
    import subprocess as sp_

    from service.conftest import server_executable
    r = sp_.run([server_executable(), "--domain", "0", "--grant", "bob=editor"], capture_output=True, text=True,
                timeout=30)
    assert r.returncode != 0 and "--grant needs --security" in r.stdout + r.stderr
    r = sp_.run([server_executable(), "--domain", "0", "--grant", "bob=owner"], capture_output=True, text=True,
                timeout=30)
    assert r.returncode != 0 and "role must be editor or viewer" in r.stdout + r.stderr
