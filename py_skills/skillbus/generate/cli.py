"""``skillbus generate CONFIG.yaml --episodes N --seed S``: docs/generate.md."""

from __future__ import annotations

import json
import sys
from pathlib import Path


def add_parser(sub) -> None:
    g = sub.add_parser("generate", help="demonstration episodes into a LeRobot dataset (docs/generate.md)")
    g.add_argument("config", help="a generation config (YAML): scene, task, randomization")
    g.add_argument("--episodes", type=int, default=10, help="how many episodes (default 10)")
    g.add_argument("--seed", type=int, default=0, help="the run's seed: episode K's seed comes from it and K alone")
    g.add_argument("--out", default=None, help="the dataset's folder (default runs/datasets/<config name>); "
                                               "episodes are appended to a dataset already there")
    g.add_argument("--workers", type=int, default=None, help="episodes at once on this machine (default: 2, or "
                                                            "the cores if fewer)")
    g.add_argument("--ray", default=None, metavar="ADDRESS",
                   help="run the episodes as tasks on this Ray cluster (\"auto\", ray://HOST:PORT), or \"local\" "
                        "for a one-node Ray instance of this machine (Ray 2.5x has no local mode)")
    g.add_argument("--first", type=int, default=0, help="the first episode's number (default 0)")
    g.add_argument("--episode", type=int, default=None, metavar="K",
                   help="run episode K alone (nothing is written to a dataset): its result and digests, to compare "
                        "with the dataset's")
    g.add_argument("--keep-work", action="store_true", help="keep each episode's folder (logs, scene, LCM log)")
    g.add_argument("--json", action="store_true", help="print the summary as JSON")


def _sigterm_as_ctrl_c(_signum, _frame) -> None:
    raise KeyboardInterrupt("SIGTERM")


def main(args) -> int:
    import signal
    from skillbus import paths
    from skillbus.generate import config as gconfig
    from skillbus.generate import runner
    try:
        cfg = gconfig.load(args.config)
    except gconfig.ConfigError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    if args.episodes < 1 or (args.workers is not None and args.workers < 1) or args.seed < 0 or args.first < 0:
        print("error: --episodes and --workers must be >= 1, --seed and --first >= 0", file=sys.stderr)
        return 2
    out = Path(args.out) if args.out else paths.REPO_ROOT / "runs" / "datasets" / cfg.path.stem.replace(".", "_")
    if args.episode is not None:
        from skillbus.generate.episode import EpisodeError, run_episode
        work = out / "work-alone"
        try:
            r = run_episode(cfg, args.seed, args.episode, work)
        except (EpisodeError, gconfig.ConfigError) as e:
            print(f"error: episode {args.episode}: {e}", file=sys.stderr)
            return 1
        r.pop("episode")
        print(json.dumps({k: r[k] for k in ("request", "seed", "success", "failure_reason", "state_digest",
                                            "session_digest", "sim_s", "wall_s")}))
        return 0
    workers = args.workers or runner.default_workers()
    signal.signal(signal.SIGTERM, _sigterm_as_ctrl_c)  # `kill PID`, a supervisor's stop: as Ctrl-C
    bar = _bar(args.episodes)
    try:
        summary = runner.generate(cfg, out, args.episodes, args.seed, workers=workers, first=args.first, ray=args.ray,
                                  progress=bar.update_to, keep_work=args.keep_work)
    except gconfig.ConfigError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except ValueError as e:  # the dataset in --out cannot take these episodes (damaged, other features)
        print(f"error: the dataset {out}: {e}", file=sys.stderr)
        return 2
    finally:
        bar.close()
    if summary.interrupted:
        print(f"interrupted: {summary.written} episode(s) written to {out}, each whole (the rest not run or cut "
              f"short, none of it written)", file=sys.stderr)
        return 130
    if args.json:
        print(json.dumps({"out": str(out), "written": summary.written, "successes": summary.successes,
                          "broken": summary.broken, "retried": summary.retried,
                          "retries": summary.retries, "wall_s": summary.wall_s,
                          "failures": dict(summary.failures),
                          "episodes": {str(k): v for k, v in summary.results.items()}}))
    else:
        print(f"dataset: {out}")
        for line in summary.lines(1 if args.ray else workers):
            print(line)
    return 0 if summary.written == args.episodes else 1


class _bar:
    """A progress bar on stderr (tqdm), advanced to a count."""

    def __init__(self, total: int) -> None:
        from tqdm import tqdm
        self.t = tqdm(total=total, unit="episode", file=sys.stderr, dynamic_ncols=True)

    def update_to(self, n: int, total: int) -> None:
        self.t.update(n - self.t.n)

    def close(self) -> None:
        self.t.close()
