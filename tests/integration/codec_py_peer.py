"""The Python half of the cross-language codec test (runs inside the sandbox).
  --publish SECONDS      publish every canonical sample on SB_CODEC_P2C_<type>
  --check SECONDS TYPE.. receive SB_CODEC_C2P_<type> from codec_peer (C++), decode it, and
                         compare it field by field and byte for byte with the Python sample"""

import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from codec_samples import samples  # noqa: E402

from skillbus.bus import open_bus  # noqa: E402
from skillbus.msgs import decode  # noqa: E402
from skillbus.waiting import poll_until  # noqa: E402


def fields(v):
    """A message as plain data (nested messages as dicts, arrays as lists) for comparison."""
    if hasattr(v, "__slots__"):
        return {slot: fields(getattr(v, slot)) for slot in v.__slots__}
    if isinstance(v, (list, tuple)):
        return [fields(x) for x in v]
    return v


def main() -> int:
    mode, seconds = sys.argv[1], float(sys.argv[2])
    bus = open_bus()
    want = samples()
    end = time.monotonic() + seconds
    if mode == "--publish":
        while time.monotonic() < end:
            for name, msg in want.items():
                bus.publish(f"SB_CODEC_P2C_{name}", msg.encode())
            time.sleep(0.02)
        return 0
    verdict = {}

    def check(name):
        def on(ch, data):
            if name in verdict:
                return
            msg = decode(type(want[name]), data)
            if msg is None:
                verdict[name] = "does not decode"
            elif fields(msg) != fields(want[name]):
                verdict[name] = f"fields differ: {fields(msg)} != {fields(want[name])}"
            elif data != want[name].encode():
                verdict[name] = "bytes differ from the Python encoding"
            else:
                verdict[name] = "ok"
        return on

    for name in sys.argv[3:]:
        bus.subscribe(f"SB_CODEC_C2P_{name}", check(name))
    poll_until(lambda: len(verdict) >= len(sys.argv[3:]), max(0.0, end - time.monotonic()), step=bus.handle)
    print(json.dumps({n: verdict.get(n, "never received") for n in sys.argv[3:]}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
