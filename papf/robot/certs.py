"""The secure split: Zenoh TLS, user/password and access control (docs/architecture.md "Transport", docs/robot.md).

:func:`write_bundle` writes a test CA, robot and laptop certificates (openssl), a password
dictionary and the Zenoh configs of the robot's router, its nodes, the laptop and an
observer; :func:`access_control` lets each role put only on its own keys (default deny).
Used by ``papf make-certs``.
With ``--ros rmw_zenoh`` the secure router is the robot's ROS 2 router ``rmw_zenohd``, in the
form rmw_zenoh's config files take (:mod:`papf.robot.rmw_bundle`).
"""

from __future__ import annotations

import ipaddress
import json
import os
import re
import secrets
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

from common.errors import ConfigError
from common.ros_link import BridgeTopics
from papf.robot.rmw_bundle import PAPF_PORT, rmw_configs

LOCAL_PORT = 7447   # [-] TCP on the robot's loopback (robot nodes, the bridge)
TLS_PORT = 7448     # [-] TLS on the robot's network interfaces (the laptop)
CERT_DAYS = 30      # [days] a test bundle, not a PKI
CURVE = "prime256v1"

# role -> (our topic suffixes it may put on, bridge topics (BridgeTopics fields) it may put on)
ROLES: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "robot": (("odom", "wheels", "clock", "scan", "events", "battery/measured", "sim/pose"),
              ("cmd_vel", "odometry", "battery", "scan")),
    "planner": (("cmd_vel", "goal", "planner/state", "planner/status", "battery", "events",
                 "scan"), ()),
    "observer": ((), ()),
}
# role -> what a connection must show besides the role's password (Zenoh ACL subject fields)
BINDINGS: dict[str, dict[str, list[str]]] = {
    "robot": {"link_protocols": ["tcp"]},          # the loopback listener: on the robot only
    "planner": {"cert_common_names": ["laptop"]},  # TLS with the laptop's certificate
    "observer": {"cert_common_names": ["laptop"]},
}
HOST_FILES = {
    "robot": ("ca.pem", "robot.pem", "robot.key", "credentials.txt", "router.json5",
              "robot.json5"),
    "laptop": ("ca.pem", "laptop.pem", "laptop.key", "laptop.json5", "observer.json5"),
}
RMW_ROBOT_FILES = ("rmw_zenohd.json5", "ros_session.json5")   # robot's too, with --ros rmw_zenoh
BUNDLE_FILES = ("ca.pem", "ca.key", "robot.pem", "robot.key", "laptop.pem", "laptop.key",
                "credentials.txt", "router.json5", "robot.json5", "laptop.json5",
                "observer.json5", "README.txt", *RMW_ROBOT_FILES)
_LABEL = re.compile(r"^(?!-)[A-Za-z0-9-]{1,63}(?<!-)$")
READ_ONLY = ("observer",)   # identities that watch: no puts, no queries (a query may set parameters)
# every message type that is not a data write: declarations, queries, liveliness
NON_PUT = ("declare_subscriber", "declare_queryable", "query", "reply", "liveliness_token",
           "liveliness_query", "declare_liveliness_subscriber")


def access_control(namespace: str = "rosbot", bridge: BridgeTopics | None = None,
                   ros_domain: int | None = None) -> dict:
    """The ``access_control`` section for the robot's router.

    Default deny. Every authenticated identity may subscribe and hold liveliness tokens, and
    receive every publication; each role may *put* only on the keys of :data:`ROLES`. Only
    ``planner`` may put on ``<ns>/cmd_vel`` and only ``robot`` (the base driver) on the
    bridge's ``cmd_vel``; ``observer`` puts nothing and queries nothing (:data:`READ_ONLY`: a
    query on ``<ns>/planner/params`` can set parameters). Zenoh 1.x decides explicit deny >
    explicit allow > default, and a rule's key expression must include the message key, so
    "everything but cmd_vel" is written as the list of allowed keys, generated from this
    table. With ``ros_domain``, ``robot``'s ROS keys are rmw_zenoh's whole domain
    (``<domain>/**``) instead of the bridge's topics, and rmw_zenoh's liveliness tokens
    (``@ros2_lv/**``; a chunk ``**`` does not match them) may be declared.
    """
    bridge = bridge or BridgeTopics()
    # "**" matches no "@" chunk: the bridge's node list (admin space) or rmw_zenoh's tokens
    anywhere = ["**", "@/*/ros2/**"] if ros_domain is None else ["**", "@ros2_lv/**"]
    rules = [
        {"id": "talk", "permission": "allow", "flows": ["ingress", "egress"],
         "messages": [m for m in NON_PUT if m != "query"], "key_exprs": anywhere},
        # a query may change a node (planner/params set): not for a read-only identity
        {"id": "query", "permission": "allow", "flows": ["ingress", "egress"],
         "messages": ["query"], "key_exprs": anywhere},
        {"id": "receive", "permission": "allow", "flows": ["egress"],
         "messages": ["put", "delete"], "key_exprs": ["**"]},
    ]
    subjects, policies = [], []
    for role, (ours, bridged) in ROLES.items():
        subjects.append({"id": role, "usernames": [role], **BINDINGS[role]})
        ros_keys = ([bridge.key(getattr(bridge, t)) for t in bridged] if ros_domain is None
                    else [f"{ros_domain}/**"] if bridged else [])
        keys = [f"{namespace}/{t}" for t in ours] + ros_keys
        names = ["talk", "receive"] + ([] if role in READ_ONLY else ["query"])
        if keys:
            rules.append({"id": f"{role}-puts", "permission": "allow", "flows": ["ingress"],
                          "messages": ["put"], "key_exprs": keys})
            names.append(f"{role}-puts")
        policies.append({"id": role, "rules": names, "subjects": [role]})
    return {"enabled": True, "default_permission": "deny", "rules": rules,
            "subjects": subjects, "policies": policies}


@dataclass(frozen=True)
class Bundle:
    """Paths of a generated bundle."""

    dir: Path

    def __getattr__(self, name: str) -> Path:  # bundle.router -> DIR/router.json5, ...
        files = {"ca": "ca.pem", "credentials": "credentials.txt", "router": "router.json5",
                 "robot": "robot.json5", "laptop": "laptop.json5", "observer": "observer.json5",
                 "rmw_zenohd": "rmw_zenohd.json5", "ros_session": "ros_session.json5"}
        if name not in files:
            raise AttributeError(name)
        return self.dir / files[name]


def _openssl(*args: str) -> None:
    exe = shutil.which("openssl")
    if exe is None:
        raise ConfigError("make-certs needs the openssl command (not found on PATH)")
    proc = subprocess.run([exe, *args], capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        raise ConfigError(f"openssl {args[0]} failed: {proc.stderr.strip()[-400:]}")


def check_host(host: str) -> str:
    """``host`` if it is an IP address or a DNS name; ConfigError otherwise."""
    try:
        return str(ipaddress.ip_address(host))
    except ValueError:
        pass
    name = host[:-1] if host.endswith(".") else host
    if 0 < len(name) <= 253 and all(_LABEL.match(label) for label in name.split(".")):
        return host
    raise ConfigError(f"--robot-host {host!r} is not an IP address or a DNS name "
                      "(letters, digits, '-' and '.')")


def make_certs(out: Path, robot_hosts: list[str], days: int = CERT_DAYS) -> None:
    """A test CA, ``robot`` (server + client) and ``laptop`` (client) EC certificates in ``out``."""
    key = ["-newkey", "ec", "-pkeyopt", f"ec_paramgen_curve:{CURVE}", "-nodes"]
    _openssl("req", "-x509", *key, "-keyout", str(out / "ca.key"), "-out", str(out / "ca.pem"),
             "-days", str(days), "-subj", "/CN=papf-test-ca")
    sans = ["DNS:localhost", "IP:127.0.0.1"]
    for host in robot_hosts:
        try:
            san = f"IP:{ipaddress.ip_address(host)}"
        except ValueError:
            san = f"DNS:{host}"
        if san not in sans:
            sans.append(san)
    for who, alt in (("robot", sans), ("laptop", ["DNS:laptop"])):
        ext = out / f"{who}.ext"
        ext.write_text(f"subjectAltName={','.join(alt)}\nbasicConstraints=CA:FALSE\n"
                       "keyUsage=digitalSignature\nextendedKeyUsage=serverAuth,clientAuth\n")
        _openssl("req", *key, "-keyout", str(out / f"{who}.key"), "-out", str(out / f"{who}.csr"),
                 "-subj", f"/CN={who}")
        _openssl("x509", "-req", "-in", str(out / f"{who}.csr"), "-CA", str(out / "ca.pem"),
                 "-CAkey", str(out / "ca.key"), "-CAcreateserial", "-out", str(out / f"{who}.pem"),
                 "-days", str(days), "-extfile", str(ext))
        (out / f"{who}.csr").unlink()
        ext.unlink()
    (out / "ca.srl").unlink(missing_ok=True)
    for k in out.glob("*.key"):
        k.chmod(0o600)


def _tls(who: str) -> dict:
    """TLS settings naming the bundle's files relative to the config (:func:`write_bundle`)."""
    return {"root_ca_certificate": "ca.pem", "enable_mtls": True,
            "connect_private_key": f"{who}.key", "connect_certificate": f"{who}.pem"}


def write_bundle(out: str | Path, robot_hosts: list[str], namespace: str = "rosbot",
                 bridge: BridgeTopics | None = None, local_port: int = LOCAL_PORT,
                 tls_port: int = TLS_PORT, force: bool = False, ros: str = "bridge",
                 ros_domain: int = 0, papf_port: int = PAPF_PORT) -> Bundle:
    """Certificates, credentials and the Zenoh configs (module doc) in directory ``out``:
    four for the bridge, six with ``ros="rmw_zenoh"`` (:mod:`papf.robot.rmw_bundle`).

    An existing bundle in ``out`` (its CA and passwords) is replaced only with ``force``.

    ``papf make-certs DIR --robot-host 192.168.1.10`` writes a test bundle:

    - ``ca.pem``/``ca.key`` and certificates ``robot.pem`` (server; its SANs are the
      ``--robot-host`` names/IPs plus localhost/127.0.0.1) and ``laptop.pem`` (client), made
      with the ``openssl`` CLI (the ``cryptography`` package is not a dependency);
    - ``credentials.txt``: the router's user/password dictionary, random passwords for the
      three identities of :data:`ROLES`;
    - ``router.json5`` (the robot's router: TLS listener with mutual TLS, local TCP listener,
      password dictionary, access control), ``robot.json5`` (nodes on the robot, TCP loopback),
      ``laptop.json5`` (planner host: TLS + client certificate) and ``observer.json5`` (valid
      credentials, read-only: for viewers, and to test that valid credentials alone cannot
      drive the robot).

    Identities are bound to how they connect, not to a password alone (Zenoh ACL subjects
    match user names, link protocols and certificate common names together): ``robot`` is
    the robot's password *over the loopback TCP listener* (only processes on the robot reach
    it); ``planner`` and ``observer`` are their passwords *with the laptop's certificate*
    (TLS). The robot's password over TLS, or the planner's over TCP, matches no subject and
    is denied everything.

    The configs name their files relative to themselves (``ca.pem``, not ``/home/…/ca.pem``;
    :func:`common.transport.load_config_file` resolves them), so the bundle works wherever it
    is copied. Which file goes to which host: :data:`HOST_FILES` (also written to
    ``README.txt`` in the bundle). ``ca.key`` goes nowhere: keep it where the bundle was made.
    """
    if ros not in ("bridge", "rmw_zenoh"):
        raise ConfigError(f"--ros {ros!r}: give bridge or rmw_zenoh")
    if not robot_hosts:
        raise ConfigError("give at least one --robot-host (the robot's IP or DNS name the "
                          "laptop connects to)")
    robot_hosts = [check_host(h) for h in robot_hosts]
    out = Path(out).resolve()
    # lexists: a symlink planted where a key or the passwords go counts (never written through)
    existing = [f for f in BUNDLE_FILES if os.path.lexists(out / f)]
    if existing and not force:
        raise ConfigError(f"{out} already holds a bundle ({', '.join(existing[:3])}…); "
                          "replacing it would change the CA and every password: give --force, "
                          "or another directory")
    try:
        out.mkdir(parents=True, exist_ok=True)
        if out.stat().st_mode & 0o002:   # anyone could swap a key for a link between our steps
            raise ConfigError(f"{out}: every user may write in it; keys and passwords go into "
                              "a directory only you can write (e.g. mkdir -m 700 bundle)")
        for f in existing:   # --force: the old files (or links) go, never what a link points to
            (out / f).unlink()
    except OSError as exc:
        raise ConfigError(f"cannot prepare {out}: {exc.strerror}") from None
    old_mask = os.umask(0o077)   # keys and passwords are never readable by others, not even briefly
    try:
        return _write_bundle(out, robot_hosts, namespace, bridge, local_port, tls_port, ros,
                             ros_domain, papf_port)
    finally:
        os.umask(old_mask)


def _write_secret(path: Path, text: str) -> None:
    """``path`` created new, mode 600, never through a symlink (the caller removed the old)."""
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0), 0o600)
    with os.fdopen(fd, "w", encoding="utf-8") as fh:
        fh.write(text)


def _write_bundle(out: Path, robot_hosts: list[str], namespace: str, bridge, local_port: int,
                  tls_port: int, ros: str, ros_domain: int, papf_port: int) -> Bundle:
    """:func:`write_bundle`'s files into the prepared ``out`` (under umask 077)."""
    make_certs(out, robot_hosts)
    passwords = {role: secrets.token_urlsafe(18) for role in ROLES}
    _write_secret(out / "credentials.txt", "".join(f"{u}:{p}\n" for u, p in passwords.items()))
    host = robot_hosts[0]
    local = f"tcp/127.0.0.1:{local_port}"
    remote = f"tls/[{host}]:{tls_port}" if ":" in host else f"tls/{host}:{tls_port}"
    router_tls = {**_tls("robot"), "listen_private_key": "robot.key",
                  "listen_certificate": "robot.pem"}
    configs = {
        "router": {"mode": "router",
                   "listen": {"endpoints": [local, f"tls/0.0.0.0:{tls_port}"]},
                   "transport": {"link": {"tls": router_tls},
                                 "auth": {"usrpwd": {"user": "robot", "password": passwords["robot"],
                                                     "dictionary_file": "credentials.txt"}}},
                   "access_control": access_control(namespace, bridge)},
        "robot": _client(local, "robot", passwords, None),
        "laptop": _client(remote, "planner", passwords, _tls("laptop")),
        "observer": _client(remote, "observer", passwords, _tls("laptop")),
    }
    if ros == "rmw_zenoh":
        configs.update(rmw_configs(passwords, router_tls, access_control(namespace, bridge, ros_domain),
                                   local_port, tls_port, papf_port))
    for name, conf in configs.items():   # they hold passwords
        _write_secret(out / f"{name}.json5", json.dumps(conf, indent=2) + "\n")
    _write_secret(out / "README.txt", where_files_go(ros))
    return Bundle(out)


def where_files_go(ros: str = "bridge") -> str:
    """Which bundle file goes to which host (README.txt of the bundle, make-certs' output)."""
    robot = HOST_FILES["robot"] + (RMW_ROBOT_FILES if ros == "rmw_zenoh" else ())
    return ("Copy to the robot:  " + " ".join(robot) + "\n"
            "Copy to the laptop: " + " ".join(HOST_FILES["laptop"]) + "\n"
            "Keep ca.key here (it signs certificates; no host needs it).\n"
            "The configs name these files relative to themselves: keep each host's files "
            "together in one directory.\n")


def _client(endpoint: str, user: str, passwords: dict, tls: dict | None) -> dict:
    transport: dict = {"auth": {"usrpwd": {"user": user, "password": passwords[user]}}}
    if tls:
        transport["link"] = {"tls": tls}
    return {"mode": "client", "connect": {"endpoints": [endpoint]},
            "scouting": {"multicast": {"enabled": False}}, "transport": transport}
