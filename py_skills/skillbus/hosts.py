"""Two simulated hosts on one machine: the sandbox's network namespace is host A, and a
child network namespace joined to it by a veth pair is host B.

    A: 10.77.0.1 on veth "sb-a"   <-- veth -->   B: 10.77.0.2 on veth "sb-b"

Nothing leaves the sandbox: both namespaces live inside its private one (the veth pair
is made and moved there, unprivileged inside ``unshare -rn``). Each program runs on the
host `placement` names for it (A unless named), with the bus configured for that host:

* LCM: udpm:// with ttl=1 and multicast routed over the veth on both hosts;
* DDS: dds://DOMAIN?interface=<own address>&peers=<the other's>.

Either way ``SKILLBUS_NETWORK`` names the veth, so the bus's guard (local by default,
docs/security.md) lets the process use it. Used by tests/integration/test_two_hosts.py.

Example::

    with TwoHosts(transport="dds", placement={"skills": "b"}) as box:
        procs = system.start(box, system.programs(run), run)   # skills on B, the rest on A
        box.cut()                                              # the cable pulled
"""

from __future__ import annotations

import select
import subprocess
from pathlib import Path

from skillbus.netns import Proc, Sandbox, SandboxError, dies_with_its_starter

ADDRESS = {"a": "10.77.0.1", "b": "10.77.0.2"}
VETH = {"a": "sb-a", "b": "sb-b"}


class TwoHosts(Sandbox):
    def __init__(self, log_dir: str | Path | None = None, transport: str = "lcm",
                 placement: dict[str, str] | None = None) -> None:
        super().__init__(log_dir=log_dir, transport=transport)
        self.placement = dict(placement or {})
        self.started_on: dict[str, str] = {}  # program name -> the host it was started on
        self._b: subprocess.Popen | None = None

    def __enter__(self) -> "TwoHosts":
        super().__enter__()
        try:
            if self.mode != "netns":
                raise SandboxError("two hosts need a private network namespace (unshare -rn)")
            self._make_host_b()
        except BaseException:
            super().__exit__(None, None, None)
            raise
        return self

    def __exit__(self, *exc) -> bool:
        try:
            return super().__exit__(*exc)
        finally:
            if self._b is not None:
                self._b.kill()
                self._b.wait(timeout=10)
                self._b = None

    def _make_host_b(self) -> None:
        # Host B's holder: a network namespace of its own inside A's user namespace.
        self._b = subprocess.Popen(self.prefix() + ["unshare", "-n", "--", *dies_with_its_starter("KILL"),
                                                    "sh", "-c", "echo ready && exec sleep 2147483647"],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
        ready, _, _ = select.select([self._b.stdout], [], [], 10)
        if not ready or self._b.stdout.readline().decode().strip() != "ready":
            raise SandboxError("host B's network namespace could not be made")
        self._sh("a", f"ip link add {VETH['a']} type veth peer name {VETH['b']} && "
                      f"ip link set {VETH['b']} netns {self._b.pid} && "
                      f"ip addr add {ADDRESS['a']}/24 dev {VETH['a']} && ip link set {VETH['a']} up multicast on && "
                      f"ip route replace 224.0.0.0/4 dev {VETH['a']}")
        self._sh("b", f"ip link set lo up && ip addr add {ADDRESS['b']}/24 dev {VETH['b']} && "
                      f"ip link set {VETH['b']} up multicast on && ip route add 224.0.0.0/4 dev {VETH['b']}")

    def host_prefix(self, host: str) -> list[str]:
        if host == "a":
            return self.prefix()
        return ["nsenter", "-t", str(self._b.pid), "-n", "-U", "--preserve-credentials", "--"]

    def _sh(self, host: str, command: str) -> None:
        r = subprocess.run(self.host_prefix(host) + ["sh", "-c", command], capture_output=True, text=True, timeout=20)
        if r.returncode != 0:
            raise SandboxError(f"setting up host {host.upper()}: {command}: {r.stderr.strip()}")

    def url_for(self, host: str) -> str:
        other = "b" if host == "a" else "a"
        if self.transport == "dds":
            return f"dds://{self.port % 200 + 1}?interface={ADDRESS[host]}&peers={ADDRESS[other]}"
        return f"udpm://239.255.76.67:{self.port}?ttl=1"

    def start(self, name: str, argv: list[str], env: dict[str, str] | None = None,
              host_network: bool = False) -> Proc:
        host = self.placement.get(name, "a")
        self.started_on[name] = host
        env = {**(env or {}), "SKILLBUS_BUS_URL": self.url_for(host), "SKILLBUS_NETWORK": VETH[host]}
        out, err = self.log_dir / f"{name}.out", self.log_dir / f"{name}.err"
        with open(out, "wb") as fo, open(err, "wb") as fe:
            popen = subprocess.Popen(self.host_prefix(host) + dies_with_its_starter() + [str(a) for a in argv],
                                     stdout=fo, stderr=fe,
                                     stdin=subprocess.DEVNULL, env=self.env(env), start_new_session=True)
        proc = Proc(name, popen, out, err)
        self.procs.append(proc)
        return proc

    def cut(self) -> None:
        """The cable pulled: host B's end of the veth goes down, so host A's end loses its
        carrier (as a NIC does when its cable is pulled) and A's own processes still hear
        each other (an interface taken down by hand would stop even that)."""
        self._sh("b", f"ip link set {VETH['b']} down")
