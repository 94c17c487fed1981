"""A PDO's variables read and written straight from its bytes.

python-canopen reads a PDO variable through ``pdo["name"].raw``: a lookup by name, then
a log line built (and dropped) at every read and write. Under lockstep the gripper device
sends TPDO1 at every frame its fingers move and the driver reads it at every one, so those
reads and writes were a tenth of the device's interpreter time. ``PdoCodec`` does the same
with the object dictionary's own encoders, for a map whose variables each fill whole
bytes (anything else: ``of`` answers None and canopen's own path stays).
"""

from __future__ import annotations

from typing import Any, Sequence

from canopen import objectdictionary


class PdoCodec:
    def __init__(self, fields: list[tuple[int, int, Any]], size: int) -> None:
        self._fields = fields  # (byte offset, byte length, ODVariable), in map order
        self.size = size       # bytes the map fills

    @classmethod
    def of(cls, pdo_map: Any, names: Sequence[str]) -> "PdoCodec | None":
        """The codec of `pdo_map` if its variables are exactly `names`, in order, each
        whole bytes of a number type; None otherwise."""
        variables = list(pdo_map.map)
        if [v.name for v in variables] != list(names):
            return None
        fields = []
        for v in variables:
            od = v.od
            if (v.offset % 8 or v.length % 8 or v.length != len(od) or od.data_type == objectdictionary.BOOLEAN
                    or od.data_type not in od.STRUCT_TYPES):
                return None
            fields.append((v.offset // 8, v.length // 8, od))
        return cls(fields, max(o + n for o, n, _ in fields))

    def read(self, data: bytes | bytearray) -> tuple:
        """The variables' values (ValueError when `data` is shorter than the map)."""
        if len(data) < self.size:
            raise ValueError(f"a PDO of {len(data)} bytes, {self.size} mapped")
        return tuple(od.decode_raw(bytes(data[o:o + n])) for o, n, od in self._fields)

    def write(self, pdo_map: Any, values: Sequence[Any]) -> None:
        """Sets the variables in the map's bytes (as ``pdo_map[name].raw = value`` each)."""
        data = pdo_map.data
        for (o, n, od), value in zip(self._fields, values):
            data[o:o + n] = od.encode_raw(value)
        pdo_map.update()
