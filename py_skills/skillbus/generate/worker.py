"""One episode in a worker process: ``python -m skillbus.generate.worker CONFIG SEED
REQUEST ATTEMPT WORK OUT``. The runner starts it in a PID namespace of its own
(``unshare --pid --fork --kill-child``; its first process a shell that reports how the
worker ended), so a worker that is killed takes every process of its episode with it
(the kernel ends a PID namespace with its first process): nothing of a killed episode
lingers or writes. Its result goes to
OUT (a pickle, renamed into place whole); an episode that could not be run writes
``{"error": ...}``."""

from __future__ import annotations

import os
import pickle
import sys
from pathlib import Path


def main(argv: list[str]) -> int:
    from skillbus.generate.config import load
    from skillbus.generate.episode import EpisodeError, run_episode
    config, seed, request, attempt, work, out = argv
    try:
        r = run_episode(load(config), int(seed), int(request), Path(work), int(attempt))
    except EpisodeError as e:
        r = {"error": str(e)}
    tmp = Path(out + ".tmp")
    tmp.write_bytes(pickle.dumps(r))
    os.replace(tmp, out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
