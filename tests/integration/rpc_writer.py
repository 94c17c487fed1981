"""An RPC client process for tests/integration/test_rpc_processes.py: makes N `add` calls on
the COUNTER service (amounts 1..N to key KEY) through a bus that drops every k-th message
it publishes, then prints a JSON summary."""

import json
import sys
import time

from skillbus.bus import DropEveryNthBus, open_bus
from skillbus.msgs import rpc_counter_t
from skillbus.rpc import RpcClient, RpcError


def main() -> int:
    key, n, drop_every, timeout = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4])
    bus = DropEveryNthBus(open_bus(), drop_every)
    client = RpcClient(bus, "counter", key)
    errors = []
    t0 = time.monotonic()
    for i in range(1, n + 1):
        r = rpc_counter_t()
        r.key, r.amount = key, i
        try:
            client.call("add", r, rpc_counter_t, timeout=timeout, retry_interval=0.02)
        except RpcError as e:
            errors.append(str(e))
    print(json.dumps({"key": key, "calls": n, "errors": errors[:5], "n_errors": len(errors),
                      "retries": client.retries, "dropped": bus.dropped,
                      "seconds": time.monotonic() - t0}), flush=True)
    return 0 if not errors else 1


if __name__ == "__main__":
    sys.exit(main())
