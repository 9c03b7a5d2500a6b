"""Who may reach the WebXR server: loopback by default, a token elsewhere, same-origin WebSockets, TLS.

- **Loopback** (``127.0.0.1``, ``::1``, ``localhost``) is the default. There
  the server still checks the ``Host`` header (only ``127.0.0.1:PORT``,
  ``localhost:PORT``, ``[::1]:PORT``), so that a web page elsewhere cannot
  reach it through a DNS name rebound to 127.0.0.1.
- **Another interface** (``--host 0.0.0.0`` or a LAN address, for a standalone
  headset on the same network) requires a random **token** in the URL: the page
  lives under ``/<token>/`` and every request outside it is refused with 403
  and a message (:meth:`Access.refusal`).
- **WebSockets** are accepted only from the server's own origin (the
  ``Origin`` header's host equals the ``Host`` header), so another site open in
  the same browser cannot drive the patches.
- **A secure context.** WebXR runs only in a secure context: ``http://localhost``
  and ``http://127.0.0.1`` are one; a page on a LAN address is one only over
  HTTPS. :func:`self_signed_certificate` makes a certificate for the server's
  addresses on first use (with the ``cryptography`` package where it can be
  imported, else the ``openssl`` command) and keeps it in the user's
  configuration folder; the browser must be told to trust it once
  (``docs/vr/webxr.md``). For a Quest on USB, ``adb reverse tcp:PORT tcp:PORT``
  makes the headset's ``localhost:PORT`` the workbench's, which needs neither.
"""

from __future__ import annotations

import datetime
import hashlib
import ipaddress
import json
import secrets
import shutil
import socket
import ssl
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

from workbench.errors import InputError

__all__ = [
    "LOOPBACK_NAMES",
    "is_loopback",
    "new_token",
    "lan_address",
    "Access",
    "Certificate",
    "self_signed_certificate",
    "certificate_folder",
]

LOOPBACK_NAMES = ("127.0.0.1", "localhost", "::1")
"""Host names that reach this computer only."""

_CERTIFICATE_DAYS = 825  # the longest validity Apple and Chrome accept for a leaf certificate


def is_loopback(host: str) -> bool:
    """Whether listening on ``host`` reaches this computer only."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def new_token() -> str:
    """A random URL-safe token (128 bits)."""
    return secrets.token_urlsafe(16)


def lan_address() -> str:
    """This computer's address on the network its default route leaves by (no packet is sent);
    ``127.0.0.1`` where there is no route."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.connect(("192.0.2.1", 9))  # TEST-NET-1: a route lookup only, nothing is sent
            return probe.getsockname()[0]
        except OSError:
            return "127.0.0.1"


def _host_name(header: str) -> str:
    """The host of a ``Host``/``Origin`` value, lower case, without port or brackets."""
    text = header.strip().lower()
    if "://" in text:
        text = text.split("://", 1)[1]
    text = text.split("/", 1)[0]
    if text.startswith("["):
        return text[1:text.find("]")] if "]" in text else text[1:]
    return text.rsplit(":", 1)[0] if text.count(":") == 1 else text


@dataclass(frozen=True)
class Access:
    """The server's access rules (module doc).

    Attributes
    ----------
    host : str
        The address it listens on.
    port : int
    token : str or None
        Required path prefix ``/<token>/``; ``None`` on loopback.
    """

    host: str
    port: int
    token: str | None

    @classmethod
    def for_host(cls, host: str, port: int, token: str | None = None) -> "Access":
        """Loopback: no token; another interface: ``token`` or a new random one."""
        if is_loopback(host):
            return cls(host, port, None)
        return cls(host, port, token or new_token())

    @property
    def base_path(self) -> str:
        """``/`` or ``/<token>/``: where the page and everything it loads live."""
        return "/" if self.token is None else f"/{self.token}/"

    def host_allowed(self, host_header: str | None) -> bool:
        """Whether a request's ``Host`` header names this server (loopback: loopback names only)."""
        if not host_header:
            return False
        if self.token is not None:
            return True  # the token is the secret; the headset may call the computer by any name
        return _host_name(host_header) in LOOPBACK_NAMES

    def origin_allowed(self, origin: str | None, host_header: str | None) -> bool:
        """Whether a WebSocket's ``Origin`` is this server's own (same host and port as ``Host``)."""
        if not origin or not host_header:
            return False
        text = origin.strip().lower()
        if "://" not in text:
            return False
        return text.split("://", 1)[1].rstrip("/") == host_header.strip().lower()

    def path_allowed(self, path: str) -> bool:
        """Whether ``path`` lies under :attr:`base_path` (the token, where there is one)."""
        if self.token is None:
            return True
        return path == self.base_path.rstrip("/") or path.startswith(self.base_path)

    def refusal(self, what: str) -> str:
        """The 403 message for a request refused for ``what`` (the missing token, a foreign Host, ...)."""
        return (f"403 Forbidden: {what}. This is the VR colour workbench's WebXR server; open the URL "
                "that `python -m workbench vr serve` (or measure --display webxr) printed, token "
                "included, or scan its QR code.")


@dataclass(frozen=True)
class Certificate:
    """A self-signed TLS certificate for the server.

    Attributes
    ----------
    cert_path, key_path : Path
        PEM files.
    names : tuple of str
        The host names and addresses it is valid for.
    sha256 : str
        Its fingerprint (``AB:CD:...``), as browsers show it.
    """

    cert_path: Path
    key_path: Path
    names: tuple
    sha256: str

    def ssl_context(self) -> ssl.SSLContext:
        """A server-side TLS context holding the certificate."""
        context = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
        context.load_cert_chain(str(self.cert_path), str(self.key_path))
        return context


def certificate_folder() -> Path:
    """Where the self-signed certificate is kept (the user's configuration folder)."""
    import platformdirs

    return Path(platformdirs.user_config_dir("vr-colour-workbench")) / "webxr-tls"


def _fingerprint(cert_path: Path) -> str:
    der = ssl.PEM_cert_to_DER_cert(cert_path.read_text(encoding="ascii"))
    digest = hashlib.sha256(der).hexdigest().upper()
    return ":".join(digest[i:i + 2] for i in range(0, len(digest), 2))


def self_signed_certificate(names, folder=None) -> Certificate:
    """The self-signed certificate in ``folder`` valid for ``names``, made there on first use.

    An existing one is kept while it covers every name and has not expired;
    otherwise a new key and certificate replace it (the browser must then be
    told to trust the new one).

    Raises
    ------
    InputError
        When neither the ``cryptography`` package nor the ``openssl`` command
        is available, or the folder cannot be written.
    """
    folder = Path(folder) if folder is not None else certificate_folder()
    wanted = tuple(dict.fromkeys(str(name) for name in names))
    cert_path, key_path, names_path = folder / "cert.pem", folder / "key.pem", folder / "names.json"
    if cert_path.is_file() and key_path.is_file() and names_path.is_file():
        try:
            recorded = json.loads(names_path.read_text(encoding="utf-8"))
            fresh = datetime.datetime.fromisoformat(recorded["not_after"]) > \
                datetime.datetime.now(datetime.timezone.utc) + datetime.timedelta(days=1)
            if fresh and set(wanted) <= set(recorded["names"]):
                return Certificate(cert_path, key_path, tuple(recorded["names"]), _fingerprint(cert_path))
        except (OSError, ValueError, KeyError, TypeError):
            pass  # unreadable record: make a new certificate
    try:
        folder.mkdir(parents=True, exist_ok=True)
        not_after = _make_certificate(cert_path, key_path, wanted)
        names_path.write_text(json.dumps({"names": list(wanted), "not_after": not_after.isoformat()}),
                              encoding="utf-8")
    except OSError as error:
        raise InputError(f"cannot write the self-signed certificate into {folder} ({error}); make the "
                         "folder writable, or serve on loopback (see docs/vr/webxr.md)") from None
    return Certificate(cert_path, key_path, wanted, _fingerprint(cert_path))


def _make_certificate(cert_path: Path, key_path: Path, names: tuple) -> datetime.datetime:
    """Write a new key and certificate for ``names``; return its expiry (UTC)."""
    now = datetime.datetime.now(datetime.timezone.utc)
    not_after = now + datetime.timedelta(days=_CERTIFICATE_DAYS)
    try:
        _make_with_cryptography(cert_path, key_path, names, now, not_after)
        return not_after
    except ImportError:
        pass
    if shutil.which("openssl") is None:
        raise InputError("a self-signed certificate needs the Python package 'cryptography' "
                         "(pip install cryptography) or the 'openssl' command (apt install openssl); "
                         "or serve on loopback and reach it with adb reverse (docs/vr/webxr.md)")
    _make_with_openssl(cert_path, key_path, names)
    return not_after


def _san(name: str) -> str:
    try:
        ipaddress.ip_address(name)
        return f"IP:{name}"
    except ValueError:
        return f"DNS:{name}"


def _make_with_cryptography(cert_path, key_path, names, not_before, not_after) -> None:
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID

    key = ec.generate_private_key(ec.SECP256R1())
    subject = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "VR colour workbench (self-signed)")])
    alternative = []
    for name in names:
        try:
            alternative.append(x509.IPAddress(ipaddress.ip_address(name)))
        except ValueError:
            alternative.append(x509.DNSName(name))
    certificate = (
        x509.CertificateBuilder()
        .subject_name(subject).issuer_name(subject)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(not_before - datetime.timedelta(minutes=5))
        .not_valid_after(not_after)
        .add_extension(x509.SubjectAlternativeName(alternative), critical=False)
        .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
        .add_extension(x509.ExtendedKeyUsage([ExtendedKeyUsageOID.SERVER_AUTH]), critical=False)
        .sign(key, hashes.SHA256())
    )
    _write_private(key_path, key.private_bytes(serialization.Encoding.PEM,
                                               serialization.PrivateFormat.PKCS8,
                                               serialization.NoEncryption()))
    cert_path.write_bytes(certificate.public_bytes(serialization.Encoding.PEM))


def _make_with_openssl(cert_path: Path, key_path: Path, names: tuple) -> None:
    with tempfile.TemporaryDirectory() as work:
        key_tmp, cert_tmp = Path(work) / "key.pem", Path(work) / "cert.pem"
        command = ["openssl", "req", "-x509", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1",
                   "-nodes", "-keyout", str(key_tmp), "-out", str(cert_tmp), "-days", str(_CERTIFICATE_DAYS),
                   "-subj", "/CN=VR colour workbench (self-signed)",
                   "-addext", "subjectAltName=" + ",".join(_san(name) for name in names),
                   "-addext", "basicConstraints=critical,CA:FALSE",
                   "-addext", "extendedKeyUsage=serverAuth"]
        result = subprocess.run(command, capture_output=True, text=True, timeout=60)
        if result.returncode != 0:
            raise InputError(f"openssl could not make the self-signed certificate: "
                             f"{result.stderr.strip().splitlines()[-1] if result.stderr.strip() else result.returncode}; "
                             "install the Python package 'cryptography' instead")
        _write_private(key_path, key_tmp.read_bytes())
        cert_path.write_bytes(cert_tmp.read_bytes())


def _write_private(path: Path, data: bytes) -> None:
    """Write a private key readable by its owner only."""
    path.unlink(missing_ok=True)
    with open(path, "xb") as handle:
        path.chmod(0o600)
        handle.write(data)
