"""The CAN hub's socket: in a folder private to this user, born 0600, and a hub never
removes what is at its path unless it is a stale socket of this user's."""

import os
import stat
from pathlib import Path

import pytest

from skillbus.can import hub


def test_the_default_folder_is_this_users_and_private(monkeypatch, tmp_path):
    monkeypatch.delenv("SKILLBUS_CAN_DIR", raising=False)
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    assert hub.socket_dir() == tmp_path / "skillbus-can"
    monkeypatch.delenv("XDG_RUNTIME_DIR")
    assert hub.socket_dir() == Path(f"/tmp/skillbus-can-{os.getuid()}")


def test_a_hub_socket_is_private(monkeypatch, tmp_path):
    monkeypatch.setenv("SKILLBUS_CAN_DIR", str(tmp_path / "can"))
    h = hub.Hub(hub.socket_path("vcan7"))
    try:
        assert stat.S_IMODE(h.path.stat().st_mode) == 0o600
        assert stat.S_IMODE(h.path.parent.stat().st_mode) == 0o700
    finally:
        h.close()


def test_a_folder_open_to_others_is_refused(monkeypatch, tmp_path):
    shared = tmp_path / "shared"
    shared.mkdir()
    os.chmod(shared, 0o777)
    monkeypatch.setenv("SKILLBUS_CAN_DIR", str(shared))
    with pytest.raises(hub.UnsafePath, match="not private to this user"):
        hub.Hub(hub.socket_path("vcan0"))


def test_what_is_not_a_socket_is_never_removed(tmp_path):
    victim = tmp_path / "journal.bin"
    victim.write_text("acknowledged data")
    with pytest.raises(hub.UnsafePath, match="not a socket"):
        hub.Hub(victim)
    assert victim.read_text() == "acknowledged data"
    link = tmp_path / "link.sock"
    link.symlink_to(victim)
    with pytest.raises(hub.UnsafePath):
        hub.Hub(link)
    assert victim.exists()


def test_a_stale_socket_is_replaced(tmp_path):
    first = hub.Hub(tmp_path / "g.sock")
    first.listener.close()  # died without cleaning up
    second = hub.Hub(tmp_path / "g.sock")
    second.close()


def test_a_live_hubs_socket_is_never_taken_over(tmp_path):
    # Before, a second hub on the same channel unlinked the first one's socket: the first
    # hub's clients were cut off from everyone who connected later (one bus split in two).
    first = hub.Hub(tmp_path / "g.sock")
    try:
        inode = (tmp_path / "g.sock").stat().st_ino
        with pytest.raises(hub.UnsafePath, match="a CAN hub already serves .*g.sock: not taking its bus over"):
            hub.Hub(tmp_path / "g.sock")
        assert (tmp_path / "g.sock").stat().st_ino == inode  # the first hub's socket, untouched
    finally:
        first.close()
