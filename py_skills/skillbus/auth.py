"""Message authentication on the bus: only holders of the deployment's key command the robot.

Every message a process publishes carries a trailer after its LCM bytes (LCM decoders,
lcm-spy's included, read the fields they know and ignore what follows)::

    payload | identity (u8 length, bytes) | incarnation u64 | counter u64 | time_ns u64
            | HMAC-SHA256 (32 bytes) | u16 length of everything after the payload | "SBA1"

The HMAC (Python's ``hmac``; OpenSSL's HMAC in C++, common/src/auth.cpp: the same bytes)
covers a version tag, the channel, the payload and the trailer's fields, with the key of
the deployment. A receiver drops and counts, never hands on:

* ``unsigned``    no trailer (a process without the key, a forged message);
* ``bad_mac``     the HMAC does not verify (a wrong key, bytes changed on the way);
* ``stale``       sent more than ``window_s`` (30 s) from the receiver's wall clock: a
                  replay of an old message (hosts need clocks within that window, NTP);
* ``replayed``    the same (identity, incarnation, counter) seen before: a replay within
                  the window (a sliding window of 4,096 counters per sender incarnation);
* ``forbidden``   the sender's identity may not send on that channel (the policy,
                  skillbus.policy).

The incarnation is the sender's start time (ns): a restarted sender starts a new window.
The identity names the process (``$SKILLBUS_IDENTITY``, set per program by ``skillbus
launch``); every holder of the key can claim any identity, so the policy guards against
mistakes and misrouted programs, and the key against everyone else (docs/security.md).

Keys: a file of one hex line per key, mode 0600 (``skillbus key``): $SKILLBUS_KEY_FILE,
else ``~/.config/skillbus/bus.key`` when it exists; the first key signs,
every key verifies, so a key is rotated by putting the new one first, restarting the
programs, then removing the old one.
"""

from __future__ import annotations

import collections
import hashlib
import hmac
import os
import secrets
import stat
import struct
import time
from dataclasses import dataclass, field
from typing import NamedTuple
from pathlib import Path

MAGIC = b"SBA1"
TAG = b"skillbus-auth-v1"
MAC_SIZE = 32
WINDOW_S = 30.0
REPLAY_WINDOW = 4096  # counters per sender incarnation
_WINDOW_MASK = (1 << REPLAY_WINDOW) - 1
MAX_SENDERS = 4096    # sender incarnations remembered (the least recently heard forgotten)
KEY_ENV = "SKILLBUS_KEY_FILE"
IDENTITY_ENV = "SKILLBUS_IDENTITY"
_FIXED = struct.Struct("<QQQ")  # incarnation, counter, time_ns
REASONS = ("unsigned", "bad_mac", "stale", "replayed", "forbidden")


class KeyFileError(RuntimeError):
    """The key file cannot be used (missing, unreadable, open to others, malformed)."""


def create_key_file(path: Path, rotate: bool = False) -> Path:
    """A new random key (32 bytes) in `path`, mode 0600, its directory 0700. With `rotate`
    the new key goes first and the existing ones stay after it (verifying only)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
    old = load_keys(path) if rotate and path.exists() else []
    lines = [secrets.token_hex(32)] + [k.hex() for k in old]
    tmp = path.with_name(path.name + ".new")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w") as f:
        f.write("\n".join(lines) + "\n")
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)
    return path


def load_keys(path: Path) -> list[bytes]:
    """The keys of a key file, the signing key first. Refuses a file that others may read
    or write (the key is the robot's command authority)."""
    path = Path(path)
    try:
        st = path.stat()
        text = path.read_text()
    except OSError as e:
        raise KeyFileError(f"the bus key {path}: {e.strerror} (create one with: skillbus key create --path {path})") from None
    if stat.S_IMODE(st.st_mode) & 0o077:
        raise KeyFileError(f"the bus key {path} is readable or writable by others (mode "
                           f"{stat.S_IMODE(st.st_mode):o}): chmod 600 {path}")
    keys = []
    for n, line in enumerate(text.split("\n"), 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        try:
            k = bytes.fromhex(line)
        except ValueError:
            raise KeyFileError(f"the bus key {path}, line {n}: not hexadecimal") from None
        if len(k) < 16:
            raise KeyFileError(f"the bus key {path}, line {n}: {len(k)} bytes, at least 16 needed")
        keys.append(k)
    if not keys:
        raise KeyFileError(f"the bus key {path} holds no key")
    return keys


def default_key_path() -> Path:
    """Where `skillbus launch` keeps the deployment's key unless told otherwise."""
    base = os.environ.get("XDG_CONFIG_HOME") or str(Path.home() / ".config")
    return Path(base) / "skillbus" / "bus.key"


def key_path() -> Path | None:
    """The key file this process uses: $SKILLBUS_KEY_FILE ("none": no key), else the
    default key file when it exists, else None (an open bus)."""
    env = os.environ.get(KEY_ENV)
    if env:
        return None if env == "none" else Path(env)
    path = default_key_path()
    return path if path.exists() else None


def default_identity() -> str:
    """$SKILLBUS_IDENTITY (skillbus launch sets it per program), else "operator": a
    command line tool or a script."""
    return os.environ.get(IDENTITY_ENV) or "operator"


_KEYED: dict[tuple[bytes, str], "hmac.HMAC"] = {}


def _mac(key: bytes, channel: str, payload: bytes, fields: bytes) -> bytes:
    # Keying (and hashing the tag and the channel) costs more than a short message: done
    # once per key and channel, then copied. (The channels a process hears are few; the
    # cache is bounded all the same, since names come from the wire.)
    base = _KEYED.get((key, channel))
    if base is None:
        if len(_KEYED) > 4096:
            _KEYED.clear()
        ch = channel.encode()
        base = _KEYED[(key, channel)] = hmac.new(key, TAG + struct.pack("<H", len(ch)) + ch, hashlib.sha256)
    m = base.copy()
    m.update(_U32.pack(len(payload)))
    m.update(payload)
    m.update(fields)
    return m.digest()


_U32 = struct.Struct("<I")


MAX_IDENTITY = 255  # bytes: the trailer's one-byte length


def identity_problem(identity: str) -> str:
    """Why `identity` cannot sign messages ("" when it can): 1 to 255 bytes, the trailer's
    room, as common/src/auth.cpp."""
    size = len(identity.encode("utf-8", "surrogateescape"))
    if 1 <= size <= MAX_IDENTITY:
        return ""
    return (f"the bus identity {identity[:40]!r}{'...' if len(identity) > 40 else ''} is {size} bytes: an identity "
            f"is 1 to {MAX_IDENTITY} bytes (${IDENTITY_ENV})")


class Sealer:
    """Appends the trailer to what one process publishes."""

    def __init__(self, key: bytes, identity: str, clock=time.time_ns) -> None:
        ident = identity.encode("utf-8", "surrogateescape")
        why = identity_problem(identity)
        if why:  # (cut, it would be another identity, which the policy forbids everywhere)
            raise ValueError(why)
        self._key, self._clock = key, clock
        self._ident = bytes([len(ident)]) + ident
        self.incarnation = clock()
        self._counter = 0

    def seal(self, channel: str, payload: bytes) -> bytes:
        self._counter += 1
        fields = self._ident + _FIXED.pack(self.incarnation, self._counter, self._clock())
        body = fields + _mac(self._key, channel, payload, fields)
        return payload + body + struct.pack("<H", len(body)) + MAGIC


@dataclass
class _Window:
    highest: int = 0
    seen: int = 0  # bit i: counter highest - i was seen
    heard: float = 0.0


class Opened(NamedTuple):
    """A verified message: its payload and who signed it. (A tuple: every message received
    makes one.)"""
    payload: bytes
    identity: str


class Rejected(Exception):
    def __init__(self, reason: str, detail: str, identity: str = "") -> None:
        super().__init__(f"{reason}: {detail}")
        self.reason, self.detail, self.identity = reason, detail, identity


@dataclass
class Opener:
    """Verifies and strips trailers; keeps the replay windows. `policy(identity, channel)`
    says whether that identity may send on that channel (None: anyone with the key)."""
    keys: list[bytes]
    policy: object = None
    window_s: float = WINDOW_S
    clock: object = time.time_ns
    stats: collections.Counter = field(default_factory=collections.Counter)
    _windows: "collections.OrderedDict[tuple[str, int], _Window]" = field(default_factory=collections.OrderedDict)

    def open(self, channel: str, data: bytes) -> Opened:
        """The payload and its sender; Rejected (counted in stats) otherwise."""
        try:
            opened = self._open(channel, data)
        except Rejected as r:
            self.stats[r.reason] += 1
            raise
        self.stats["ok"] += 1
        return opened

    def _open(self, channel: str, data: bytes) -> Opened:
        n = len(data)
        if n < 6 or data[-4:] != MAGIC:
            raise Rejected("unsigned", f"no authenticator on {channel} ({n} bytes)")
        (body_len,) = struct.unpack_from("<H", data, n - 6)
        start = n - 6 - body_len
        if body_len < 1 + _FIXED.size + MAC_SIZE or start < 0:
            raise Rejected("unsigned", f"a malformed authenticator on {channel}")
        body = data[start:n - 6]
        id_len = body[0]
        if 1 + id_len + _FIXED.size + MAC_SIZE != body_len:
            raise Rejected("unsigned", f"a malformed authenticator on {channel}")
        fields, mac = body[:-MAC_SIZE], body[-MAC_SIZE:]
        payload = data[:start]
        if not any(hmac.compare_digest(_mac(k, channel, payload, fields), mac) for k in self.keys):
            raise Rejected("bad_mac", f"the authenticator of a message on {channel} does not verify (another key?)")
        identity = fields[1:1 + id_len].decode("utf-8", "replace")
        incarnation, counter, sent_ns = _FIXED.unpack_from(fields, 1 + id_len)
        now = self.clock()
        if abs(now - sent_ns) > self.window_s * 1e9:
            raise Rejected("stale", f"{identity} on {channel}: sent {(now - sent_ns) / 1e9:.1f} s from now "
                                    f"(window {self.window_s:g} s)", identity)
        if self.policy is not None and not self.policy(identity, channel):
            raise Rejected("forbidden", f"{identity} may not send on {channel}", identity)
        self._check_replay(identity, incarnation, counter, now, channel)
        return Opened(payload, identity)

    def _check_replay(self, identity: str, incarnation: int, counter: int, now: int, channel: str) -> None:
        key = (identity, incarnation)
        w = self._windows.get(key)
        if w is None:
            w = self._windows[key] = _Window(highest=counter, seen=1, heard=now)
            self._forget(now)
            return
        self._windows.move_to_end(key)
        w.heard = now
        if counter > w.highest:
            shift = counter - w.highest
            w.seen = ((w.seen << shift) | 1) & _WINDOW_MASK if shift < REPLAY_WINDOW else 1
            w.highest = counter
            return
        age = w.highest - counter
        if age >= REPLAY_WINDOW or (w.seen >> age) & 1:
            raise Rejected("replayed", f"{identity} on {channel}: message {counter} seen before", identity)
        w.seen |= 1 << age

    def _forget(self, now: int) -> None:
        """Senders silent for longer than the window can be forgotten: any message of
        theirs from before is stale by now. At most MAX_SENDERS are kept."""
        horizon = now - self.window_s * 1e9
        while self._windows:
            k, w = next(iter(self._windows.items()))
            if w.heard < horizon or len(self._windows) > MAX_SENDERS:
                self._windows.popitem(last=False)
            else:
                break


class NativeOpener:
    """Opener's interface (open, stats) over skillbus_native.Opener: the C++ twin of the
    same rules (common/src/auth.cpp), at a fifth of the Python one's cost."""

    def __init__(self, lib, keys: list[bytes], policy_text: str | None) -> None:
        self.core = lib.Opener(list(keys), policy_text)  # (shared with skillbus.quiet_frames)
        self._open = self.core.open
        self.stats: collections.Counter = collections.Counter()

    def open(self, channel: str, data: bytes) -> Opened:
        ok, got, identity, why = self._open(channel, data)
        if ok:
            self.stats["ok"] += 1
            return Opened(got, identity)
        self.stats[got] += 1
        raise Rejected(got, why, identity)


def bus_sealer(key: bytes, identity: str):
    """The sealer a bus signs with: skillbus_native's when built (skillbus.native), else
    Sealer; both write the same trailer."""
    from skillbus import native
    lib = native.module()
    why = identity_problem(identity)
    if lib is None or why:
        return Sealer(key, identity)  # (which names a bad identity)
    return lib.Sealer(key, identity.encode("utf-8", "surrogateescape"))


def bus_opener(keys: list[bytes], policy=None):
    """The opener a bus verifies with: skillbus_native's when built and the policy is a
    skillbus.policy.Policy (or none), else Opener; both apply the same rules."""
    from skillbus import native
    from skillbus.policy import Policy
    lib = native.module()
    if lib is None or not (policy is None or isinstance(policy, Policy)):
        return Opener(keys, policy=policy)
    return NativeOpener(lib, keys, None if policy is None else policy.text())


def strip(data: bytes) -> bytes:
    """The payload of a message with or without a trailer, unverified: for reading logs
    (lcm-logger keeps what was on the wire), never for acting on a message."""
    n = len(data)
    if n >= 6 and data[-4:] == MAGIC:
        (body_len,) = struct.unpack_from("<H", data, n - 6)
        if 0 <= n - 6 - body_len:
            return data[:n - 6 - body_len]
    return data
