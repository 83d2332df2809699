"""DDS Security for the client (proto/PROTOCOL.md, "Security"): :class:`SecurityConfig`.

The configuration file is the server's (``surfeledit-server --security``): ``key = value`` lines
naming one participant's identity, the two CAs and the signed governance and permissions documents
(``scripts/make_security.py`` writes one per user), plus the optional ``plugin_dir`` and ``user``.
:meth:`SecurityConfig.qos_properties` turns it into the ``dds.sec.*`` participant QoS properties of
Cyclone's built-in authentication, access-control and cryptography plugins.

Only a binding linked with a ``libddsc`` that has those plugins can use it: the cyclonedds 0.10
binding of ``.venv-secure`` (built against Debian's library by ``scripts/setup.sh``); the pip wheel
of cyclonedds 11 has none, and :meth:`SecurityConfig.plugin_directory` says so with a typed error.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import re
import threading
from pathlib import Path
from typing import Dict, Iterator, List, Optional, Tuple, Union

from cyclonedds.core import DDSException
from cyclonedds.qos import Policy, Qos

from .errors import AccessDeniedError, InvalidArgumentError, SecurityConfigError

__all__ = ["SecurityConfig", "FILE_KEYS", "plugin_directory", "security_available", "claim_identity", "release_identity", "security_config", "participant_qos", "access_checked"]

#: Configuration key -> participant QoS property (OMG DDS Security, built-in plugins).
FILE_KEYS: Dict[str, str] = {
    "identity_ca": "dds.sec.auth.identity_ca",
    "identity_certificate": "dds.sec.auth.identity_certificate",
    "private_key": "dds.sec.auth.private_key",
    "permissions_ca": "dds.sec.access.permissions_ca",
    "governance": "dds.sec.access.governance",
    "permissions": "dds.sec.access.permissions",
}

# The three plugins: property prefix, library file, init and finalize functions.
_PLUGINS: Tuple[Tuple[str, str, str, str], ...] = (
    ("dds.sec.auth.library.", "libdds_security_auth.so", "init_authentication", "finalize_authentication"),
    ("dds.sec.crypto.library.", "libdds_security_crypto.so", "init_crypto", "finalize_crypto"),
    ("dds.sec.access.library.", "libdds_security_ac.so", "init_access_control", "finalize_access_control"),
)

# A user name as make_security.py accepts it (the certificate's CN).
_USER = re.compile(r"^[A-Za-z0-9_-]{1,64}$")


@dataclasses.dataclass(frozen=True)
class SecurityConfig:
    """One participant's DDS Security files (absolute paths once loaded with :meth:`load`)."""

    identity_ca: Path  # PEM: the CA that signed every participant's certificate
    identity_certificate: Path  # PEM: this participant's X.509 certificate (subject CN=<user>)
    private_key: Path  # PEM: its private key (unencrypted)
    permissions_ca: Path  # PEM: the CA that signed governance and permissions
    governance: Path  # S/MIME-signed governance document (.p7s)
    permissions: Path  # S/MIME-signed permissions document of this participant (.p7s)
    # The user name the permissions grant to (the certificate's CN); the client id is prefixed with
    # it, because the demo permissions let a user read replies only in "surfeledit.reply.<user>.*".
    user: Optional[str] = None
    # Directory of libdds_security_{auth,ac,crypto}.so; None: next to the binding's libddsc.
    plugin_dir: Optional[Path] = None

    @classmethod
    def load(cls, path: Union[str, "os.PathLike[str]"]) -> "SecurityConfig":
        """Reads a configuration file; relative paths in it are relative to the file. Every named
        file must be a readable regular file. Raises :class:`SecurityConfigError` naming the line or key."""
        path = Path(path)
        try:
            text = path.read_text()
        except OSError as e:
            raise SecurityConfigError(f"security config '{path}' cannot be read: {e.strerror}", "security") from None
        base = path.resolve().parent
        values: Dict[str, str] = {}
        for number, raw in enumerate(text.splitlines(), 1):
            line = raw.strip()
            if not line or line.startswith("#"):
                continue
            key, sep, value = (s.strip() for s in line.partition("="))
            if not sep:
                raise SecurityConfigError(f"security config '{path}' line {number}: expected 'key = value', "
                                          f"got {line!r}", "security")
            if key not in FILE_KEYS and key not in ("plugin_dir", "user"):
                raise SecurityConfigError(f"security config '{path}' line {number}: unknown key {key!r}", key)
            if not value:
                raise SecurityConfigError(f"security config '{path}' line {number}: empty value for {key!r}", key)
            if key in values:
                raise SecurityConfigError(f"security config '{path}' line {number}: {key!r} given twice", key)
            values[key] = value
        files: Dict[str, Path] = {}
        for key in FILE_KEYS:
            if key not in values:
                raise SecurityConfigError(f"security config '{path}': missing key {key!r}", key)
            files[key] = _regular_file(path, key, values[key], base)
        user = values.get("user")
        if user is not None and not _USER.match(user):
            raise SecurityConfigError(f"security config '{path}': user {user!r}: letters, digits, - and _ only", "user")
        plugin_dir = values.get("plugin_dir")
        return cls(user=user, plugin_dir=(base / plugin_dir) if plugin_dir else None, **files)

    def plugin_directory(self) -> Path:
        """The directory holding the three plugin libraries (:func:`plugin_directory`)."""
        return plugin_directory(self.plugin_dir)

    def qos_properties(self) -> List[Tuple[str, str]]:
        """The participant QoS properties (name, value): six files and three plugins."""
        props = [(prop, "file:" + str(getattr(self, key))) for key, prop in FILE_KEYS.items()]
        d = self.plugin_directory()
        for prefix, name, init, fini in _PLUGINS:
            props += [(prefix + "path", str(d / name)), (prefix + "init", init), (prefix + "finalize", fini)]
        return props

    def client_id_prefix(self) -> str:
        """``"<user>."`` (the start of every client id of this identity), or "" without ``user``."""
        return f"{self.user}." if self.user else ""


def plugin_directory(plugin_dir: Optional[Path] = None) -> Path:
    """The directory holding ``libdds_security_{auth,ac,crypto}.so``: ``plugin_dir``, or the one next
    to the ``libddsc`` the cyclonedds binding loaded (Debian: its ``libddsc0debian`` subdirectory).
    Raises :class:`SecurityConfigError` when they are not there (the pip wheel of cyclonedds 11)."""
    if plugin_dir is not None:
        candidates = [Path(plugin_dir)]
    else:
        lib = _loaded_libddsc()
        candidates = [lib.parent, lib.parent / "libddsc0debian"] if lib else []
    for d in candidates:
        if all((d / name).is_file() for _, name, _, _ in _PLUGINS):
            return d.resolve()
    where = ", ".join(str(d) for d in candidates) or "(libddsc not found)"
    raise SecurityConfigError(
        f"no DDS Security plugins (libdds_security_auth.so, _ac, _crypto) in {where}: the cyclonedds "
        "binding in use has none (the pip wheel of cyclonedds 11); run with .venv-secure "
        "(scripts/setup.sh) or set plugin_dir", "plugin_dir")


def security_available() -> bool:
    """Whether this cyclonedds binding can run DDS Security (its libddsc has the plugins beside it)."""
    try:
        plugin_directory()
    except SecurityConfigError:
        return False
    return True


def security_config(security: Optional[Union[str, "os.PathLike[str]", SecurityConfig]]) -> Optional[SecurityConfig]:
    """``connect(security=...)``: None, a loaded config, or a file to load."""
    if security is None or isinstance(security, SecurityConfig):
        return security
    if isinstance(security, (str, os.PathLike)):
        return SecurityConfig.load(security)
    raise InvalidArgumentError(f"security {security!r}: expected a path or a SecurityConfig", "security")


def participant_qos(security: Optional[SecurityConfig]) -> Optional[Qos]:
    """The participant's QoS: Cyclone's defaults, or its DDS Security properties (security.py)."""
    if security is None:
        return None
    return Qos(*[Policy.Property(name, value) for name, value in security.qos_properties()])


@contextlib.contextmanager
def access_checked(security: Optional[SecurityConfig], entity: str) -> Iterator[None]:
    """With DDS Security, Cyclone refuses to create an entity the identity or permissions do not
    allow (DDSException): raised as AccessDeniedError naming the entity."""
    try:
        yield
    except DDSException as e:
        if security is None:
            raise
        raise AccessDeniedError(
            f"DDS Security refused the {entity} of identity {security.identity_certificate.name} "
            f"({security.user or 'no user'}): {e}", entity) from None


# The identity (certificate path) of this process's secured clients and how many are open.
_identity_lock = threading.Lock()
_identity: Optional[Path] = None
_identity_users = 0


def claim_identity(security: Optional[SecurityConfig]) -> None:
    """Registers a secured client of this process. Cyclone 0.10.2 does not keep two identities apart
    in one process (measured: a second participant with another identity was allowed a reader
    its permissions deny, and in another run refused one they allow), so
    a client with a different certificate while one is open raises :class:`SecurityConfigError`."""
    global _identity, _identity_users
    if security is None:
        return
    with _identity_lock:
        if _identity_users and _identity != security.identity_certificate:
            raise SecurityConfigError(
                f"this process already has a secured client with identity {_identity}; one DDS Security "
                f"identity per process (not {security.identity_certificate})", "identity_certificate")
        _identity, _identity_users = security.identity_certificate, _identity_users + 1


def release_identity(security: Optional[SecurityConfig]) -> None:
    """Unregisters a client registered by :func:`claim_identity`."""
    global _identity_users
    if security is None:
        return
    with _identity_lock:
        _identity_users = max(0, _identity_users - 1)


def _regular_file(config: Path, key: str, value: str, base: Path) -> Path:
    p = Path(value)
    p = (p if p.is_absolute() else base / p).resolve()
    if not p.is_file() or not os.access(p, os.R_OK):
        raise SecurityConfigError(f"security config '{config}': {key} = '{value}' ({p}) is not a readable "
                                  "regular file", key)
    return p


def _loaded_libddsc() -> Optional[Path]:
    """The file of the libddsc the cyclonedds binding loaded (resolved), from the process's mappings."""
    try:
        import cyclonedds.internal  # noqa: F401  (loads libddsc)
        with open("/proc/self/maps") as maps:
            for line in maps:
                name = line.rsplit(None, 1)[-1]
                if os.path.basename(name).startswith("libddsc"):
                    return Path(name).resolve()
    except OSError:  # pragma: no cover - no /proc
        pass
    return None
