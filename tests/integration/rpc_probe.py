"""Reads counters from the COUNTER service, or calls a service that may not exist, and
prints the outcome as JSON (run inside the sandbox by test_rpc_processes.py)."""

import json
import sys
import time

from skillbus.bus import open_bus
from skillbus.msgs import rpc_counter_t
from skillbus.rpc import RpcClient, RpcError, RpcTimeout


def main() -> int:
    area, timeout, keys = sys.argv[1], float(sys.argv[2]), sys.argv[3:]
    client = RpcClient(open_bus(), area, "probe")
    out = {}
    for key in keys:
        r = rpc_counter_t()
        r.key = key
        t0 = time.monotonic()
        try:
            rep = client.call("get", r, rpc_counter_t, timeout=timeout)
            out[key] = {"value": rep.value, "writes": rep.writes}
        except RpcTimeout as e:
            out[key] = {"timeout": str(e), "seconds": time.monotonic() - t0}
        except RpcError as e:
            out[key] = {"error": str(e)}
    print(json.dumps(out), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
