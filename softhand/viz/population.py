"""The paper's Fig. 4, over a population of partners: each region's peak force across partners.

`population_figure` takes plain data (per partner, per region peak force; the paper's set of
regions over 2 N) and writes a PNG: top, each region's peak-force distribution over the partners
(box and points) with the 2 N line; bottom, the share of partners over 2 N per region, the regions
of the paper's Fig. 4 marked. This stage does not import the environment.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from softhand.io import atomic_open, check_writable_file

__all__ = ["population_figure"]


def population_figure(peaks: Sequence[Mapping[str, float]], paper_over_2n: Sequence[str],
                      path: str | os.PathLike, *, title: str = "") -> Path:
    """Write the figure to ``path`` (a ``.png``, atomically) and return its path.

    Args:
        peaks: one mapping region -> peak force (N) per partner, regions in one order.
        paper_over_2n: the regions the paper's Fig. 4 marks over 2 N.
        path: the PNG to write.
        title: the figure's title (what ran: hand, design, controller, n).
    """
    target = check_writable_file(path, suffix=".png")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    regions = list(peaks[0])
    data = np.array([[p[r] for r in regions] for p in peaks])
    share = 100 * (data > 2.0).mean(axis=0)
    marked = [r in set(paper_over_2n) for r in regions]
    x = np.arange(len(regions))
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(11, 7), sharex=True,
                                      gridspec_kw={"height_ratios": [2, 1]})
    top.boxplot([data[:, i] for i in range(len(regions))], positions=x, widths=0.6,
                showfliers=False)
    rng = np.random.default_rng(0)
    for i in range(len(regions)):
        top.plot(x[i] + rng.uniform(-0.15, 0.15, len(data)), data[:, i], ".", ms=4,
                 color="tab:red" if marked[i] else "tab:blue", alpha=0.6)
    top.axhline(2.0, color="k", ls="--", lw=1)
    top.text(len(regions) - 0.5, 2.0, " 2 N", va="bottom", ha="right")
    top.set_ylabel("peak force over the handshake (N)")
    top.set_title(title)
    bottom.bar(x, share, color=["tab:red" if m else "tab:blue" for m in marked])
    bottom.set_ylabel("partners over 2 N (%)")
    bottom.set_ylim(0, 100)
    bottom.set_xticks(x, regions, rotation=45, ha="right")
    for label, m in zip(bottom.get_xticklabels(), marked, strict=True):
        if m:
            label.set_fontweight("bold")
            label.set_color("tab:red")
    bottom.text(0.0, 1.02, "red (bars, points and bold names): over 2 N in the paper's Fig. 4 "
                "(30 subjects)",
                transform=bottom.transAxes, fontsize=9)
    fig.tight_layout()
    with atomic_open(target, "wb") as fh:
        fig.savefig(fh, format="png", dpi=110)
    plt.close(fig)
    return target
