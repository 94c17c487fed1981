"""Publishes bad input on the given channels: random bytes, and truncations and bit flips
of real messages of each type (seeded, so every run sends the same).
Usage: fuzz_publisher.py COUNT CHANNEL..."""

import random
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from codec_samples import samples  # noqa: E402

from skillbus.bus import open_bus  # noqa: E402


def bad_messages(rng: random.Random, count: int):
    real = [m.encode() for m in samples().values()]
    for i in range(count):
        kind = i % 3
        if kind == 0:
            yield rng.randbytes(rng.randrange(0, 200))
        elif kind == 1:
            m = rng.choice(real)
            yield m[:rng.randrange(0, len(m))]
        else:
            m = bytearray(rng.choice(real))
            for _ in range(3):
                m[rng.randrange(8, len(m))] ^= 1 << rng.randrange(8)  # keep the fingerprint
            yield bytes(m)


def main() -> int:
    count, channels = int(sys.argv[1]), sys.argv[2:]
    bus = open_bus()
    rng = random.Random(2026)
    for i, data in enumerate(bad_messages(rng, count)):
        bus.publish(channels[i % len(channels)], data)
        if i % 50 == 49:
            time.sleep(0.002)  # a flood, but not one that overflows the receivers' socket buffers
    return 0


if __name__ == "__main__":
    sys.exit(main())
