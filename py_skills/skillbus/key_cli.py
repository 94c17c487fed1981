"""``skillbus key``: the deployment's bus key (docs/security.md).

    skillbus key create [--path P]   a new key (0600), unless one is there
    skillbus key rotate [--path P]   a new signing key first, the old ones kept to verify
    skillbus key retire [--path P]   only the signing key left (after every program restarted)
    skillbus key show   [--path P]   where the key is, how many keys, the file's mode
"""

from __future__ import annotations

import argparse
import os
import stat
import sys
from pathlib import Path

from skillbus import auth


def add_parser(sub) -> None:
    k = sub.add_parser("key", help="create, rotate or show the bus key (message authentication)")
    k.add_argument("action", choices=["create", "rotate", "retire", "show"])
    k.add_argument("--path", default=None,
                   help=f"the key file (default: ${auth.KEY_ENV}, else {auth.default_key_path()})")


def main(args: argparse.Namespace) -> int:
    if args.path is not None and not args.path.strip():  # (an empty $VAR: it acted on the default key file)
        print("error: key --path: empty (give the key file, or leave --path out for the default)", file=sys.stderr)
        return 2
    env = os.environ.get(auth.KEY_ENV)
    path = Path(args.path or (env if env and env != "none" else auth.default_key_path()))
    try:
        if args.action == "create":
            if path.exists():
                auth.load_keys(path)
                print(f"{path}: a key is there already (skillbus key rotate makes a new one)")
                return 0
            auth.create_key_file(path)
            print(f"{path}: new key (mode 600); programs launched from now on use it")
        elif args.action == "rotate":
            auth.create_key_file(path, rotate=True)
            n = len(auth.load_keys(path))
            print(f"{path}: new signing key; {n - 1} older key(s) still verify. Restart every program "
                  f"(skillbus shutdown; skillbus launch), then: skillbus key retire")
        elif args.action == "retire":
            keys = auth.load_keys(path)
            tmp = path.with_name(path.name + ".new")
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
            with os.fdopen(fd, "w") as f:
                f.write(keys[0].hex() + "\n")
                f.flush()
                os.fsync(f.fileno())
            os.replace(tmp, path)
            print(f"{path}: {len(keys) - 1} older key(s) retired; only the signing key verifies now")
        else:
            keys = auth.load_keys(path)
            mode = stat.S_IMODE(path.stat().st_mode)
            print(f"{path}: {len(keys)} key(s) (the first signs), mode {mode:o}")
    except auth.KeyFileError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    return 0
