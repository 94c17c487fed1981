"""CAN traffic on record: ``skillbus can-record`` writes a bus to a candump log file
(python-can's Logger, the format of Linux's candump -l), and ``skillbus can-log`` prints
such a file decoded as CANopen: NMT commands, heartbeats and boot-ups, SDO requests and
answers with the object's name, PDOs with their mapped objects by name and value (from
the EDS, decoded by canopen's own PDO maps), and EMCY with code and text.

    skillbus can-record --channel gripper0 traffic.log --seconds 10
    skillbus can-log traffic.log --node-id 5
"""

from __future__ import annotations

import json
import signal
import struct
import sys
import time
from pathlib import Path
from typing import Iterator

import can
import canopen

from skillbus.can import cia402 as c
from skillbus.can.eds import EDS
from skillbus.record import DRAIN_S, say_drain_cut

NMT_COMMANDS = {0x01: "start", 0x02: "stop", 0x80: "enter pre-operational", 0x81: "reset node",
                0x82: "reset communication"}
NMT_STATES = {code: name for name, code in c.NMT_STATE_CODES.items()}
SDO_CLIENT = {1: "download", 2: "upload", 4: "abort"}       # ccs, bits 7-5 of byte 0
SDO_SERVER = {3: "download ok", 2: "upload answer", 4: "abort"}  # scs


FLUSH_S = 0.1  # the file is flushed this often: a recorder killed with -9 loses at most this much


def record(channel: str, path: str, interface: str = "skillbus_vcan", seconds: float | None = None) -> int:
    """Writes every frame on the bus to `path` (candump format for .log) until `seconds`
    pass or SIGINT/SIGTERM; returns how many. OSError, ValueError (a file name python-can
    has no format for) or can.CanError, before it says it records, when it cannot."""
    stop = [0]  # the signals received: one stops the recording, one more its drain

    def on_signal(*_):
        stop[0] += 1

    signal.signal(signal.SIGTERM, on_signal)
    signal.signal(signal.SIGINT, on_signal)
    bus = can.Bus(interface=interface, channel=channel)
    try:
        log = can.Logger(path)
    except BaseException:
        bus.shutdown()
        raise
    n = 0
    end = time.monotonic() + seconds if seconds is not None else None
    flushed = time.monotonic()
    try:
        # Said once the bus and the file are both open: from here on every frame is kept.
        print(f"recording {channel} to {path}", file=sys.stderr, flush=True)
        while not stop[0] and (end is None or time.monotonic() < end):
            msg = bus.recv(0.1)
            if msg is not None:
                log.on_message_received(msg)
                n += 1
            if time.monotonic() - flushed >= FLUSH_S and getattr(log, "file", None) is not None:
                log.file.flush()
                flushed = time.monotonic()
        # Stopped: the frames that reached the recorder before the stop are kept too (a
        # stop is asked for after something was sent; it must be in the log), for
        # DRAIN_S at most: a bus that sends faster than this writes would keep it forever.
        drain_end, signals_at_stop = time.monotonic() + DRAIN_S, stop[0]
        while (msg := bus.recv(0.0)) is not None:
            cut = time.monotonic() >= drain_end or stop[0] > signals_at_stop  # (and a frame still came)
            log.on_message_received(msg)
            n += 1
            if cut:
                say_drain_cut("can-record", "frames", DRAIN_S)
                break
    finally:  # nothing is lost on a stop: the file is flushed and closed
        log.stop()
        bus.shutdown()
    return n


class Decoder:
    def __init__(self, node_id: int = 5, eds: str | Path = EDS) -> None:
        self.node_id = node_id
        self.node = canopen.RemoteNode(node_id, str(eds))
        canopen.Network().add_node(self.node)  # never connected: only to read the PDO maps
        self.od = self.node.object_dictionary
        self.node.tpdo.read(from_od=True)
        self.node.rpdo.read(from_od=True)
        self.pdos = {}
        for kind, maps in (("TPDO", self.node.tpdo), ("RPDO", self.node.rpdo)):
            for num, m in maps.map.items():
                if m.cob_id and m.enabled:
                    self.pdos[m.cob_id] = (f"{kind}{num}", m)

    def _name(self, index: int, sub: int) -> str:
        try:
            obj = self.od[index]
            if isinstance(obj, canopen.objectdictionary.Variable):
                return f"0x{index:04X} {obj.name}"
            return f"0x{index:04X}sub{sub} {obj.name}.{obj[sub].name}"
        except KeyError:
            return f"0x{index:04X}sub{sub} (not in the EDS)"

    def decode(self, msg: can.Message) -> str:
        cid, data, nid = msg.arbitration_id, bytes(msg.data), self.node_id
        if cid == 0x000 and len(data) == 2:
            return f"NMT {NMT_COMMANDS.get(data[0], f'command 0x{data[0]:02X}')} node {data[1] or 'all'}"
        if cid == 0x080:
            return "SYNC"
        if cid in self.pdos:
            name, m = self.pdos[cid]
            if len(data) != len(m.data):
                return f"{name} of {len(data)} bytes ({len(m.data)} mapped): malformed"
            m.data = bytearray(data)
            fields = ", ".join(f"{v.name}={v.raw}" for v in m.map)
            extra = ""
            if name == "TPDO1":
                extra = f" [{c.state_of(m.map[0].raw)}]"
            return f"{name} {fields}{extra}"
        if cid == 0x080 + nid:
            if not data:
                return "EMCY (empty)"
            code = struct.unpack_from("<H", data)[0]
            if code == 0:
                return "EMCY error reset"
            return f"EMCY 0x{code:04X} {c.EMCY_TEXT.get(code, 'device error')}, register 0x{data[2]:02X}"
        if cid in (0x600 + nid, 0x580 + nid) and len(data) == 8:
            role = "request" if cid == 0x600 + nid else "answer"
            spec = (data[0] >> 5) & 7
            index, sub = struct.unpack_from("<HB", data, 1)
            what = (SDO_CLIENT if role == "request" else SDO_SERVER).get(spec, f"command {spec}")
            if spec == 4:
                abort = struct.unpack_from("<I", data, 4)[0]
                return f"SDO {role} abort {self._name(index, sub)}: code 0x{abort:08X}"
            value = ""
            if (data[0] & 0x02) and ((role == "request" and spec == 1) or (role == "answer" and spec == 2)):
                size = 4 - ((data[0] >> 2) & 3) if data[0] & 0x01 else 4
                value = f" = {int.from_bytes(data[4:4 + size], 'little')}"
            return f"SDO {role} {what} {self._name(index, sub)}{value}"
        if cid == 0x700 + nid and len(data) == 1:
            if data[0] == 0:
                return "boot-up"
            return f"heartbeat {NMT_STATES.get(data[0], f'state 0x{data[0]:02X}')}"
        return f"unknown COB-ID 0x{cid:03X} ({len(data)} bytes)"


def frames(path: str, node_id: int = 5, eds: str | Path = EDS) -> Iterator[dict]:
    """Each frame of a log: seconds since the first, COB-ID, data (hex) and its meaning."""
    d = Decoder(node_id, eds)
    start = None
    for msg in can.LogReader(path):
        start = msg.timestamp if start is None else start
        yield {"t": msg.timestamp - start, "id": msg.arbitration_id, "data": bytes(msg.data).hex().upper(),
               "decoded": d.decode(msg)}


def lines(path: str, node_id: int = 5, eds: str | Path = EDS) -> Iterator[str]:
    for f in frames(path, node_id, eds):
        raw = f"{f['id']:03X}#{f['data']}"
        yield f"{f['t']:10.4f}  {raw:<24} {f['decoded']}"


def main_record(args) -> int:
    try:
        n = record(args.channel, args.file, args.interface, args.seconds)
    except (OSError, ValueError, can.CanError) as e:
        print(f"error: can-record {args.file} (CAN channel {args.channel}): {e}", file=sys.stderr)
        return 2
    print(f"{n} frames written to {args.file}", file=sys.stderr)
    return 0


def main_log(args) -> int:
    eds = args.eds or EDS
    try:  # the EDS first, named as itself (its error was told as the log's)
        Decoder(args.node_id, eds)
    except Exception as e:  # (canopen's import raises what it meets: ValueError, KeyError, ...)
        print(f"error: --eds {eds}: not a readable EDS ({type(e).__name__}: {e})", file=sys.stderr)
        return 2
    from can.io.blf import BLFParseError
    try:
        if getattr(args, "json", False):
            print(json.dumps(list(frames(args.file, args.node_id, args.eds or EDS))))
            return 0
        for line in lines(args.file, args.node_id, args.eds or EDS):
            print(line)
    except BrokenPipeError:
        raise  # the reader went away (| head): the CLI ends quietly
    except (OSError, ValueError, struct.error, EOFError, BLFParseError, can.CanError) as e:
        # (a file that is no log of its kind: a .blf that is not BLF ended in struct.error)
        print(f"error: {args.file}: not a readable CAN log ({type(e).__name__}: {e})", file=sys.stderr)
        return 2
    return 0
