"""The benches' plots (matplotlib, no display): one figure of one axes each, written as a
PNG into docs/images/, the same size and look for every bench.

    with figure(path, "Title", "x label", "y label") as ax:
        ax.plot(xs, ys, "o-", label="ours")
"""

from __future__ import annotations

import contextlib
from pathlib import Path
from typing import Iterator

IMAGES = Path(__file__).resolve().parent.parent / "docs" / "images"


@contextlib.contextmanager
def figure(path: Path, title: str, xlabel: str, ylabel: str, log_x: bool = False,
           log_y: bool = False) -> Iterator:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4.5))
    yield ax
    if log_x:
        ax.set_xscale("log")
    if log_y:
        ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)
