"""Frames of a handshake video (``softhand render --video``) as one labelled PNG strip.

Usage: ``python tools/video_frames.py docs/handshake.gif docs/handshake-frames.png [--at T ...]``
picks the frames nearest the times ``T`` (s; the video's frame k is at k / 12.5 s, the rate of
``softhand render --video``), default: the reach, the end of the grip, mid-shake, mid-hold, the
release and the return of the default 4.15 s handshake.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

FPS = 12.5  # softhand.cli.handshake.VIDEO_FPS
DEFAULT_AT = (0.5, 1.2, 1.9, 2.8, 3.3, 3.8)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("video")
    p.add_argument("out")
    p.add_argument("--at", type=float, nargs="+", default=list(DEFAULT_AT))
    a = p.parse_args(argv)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from PIL import Image

    with Image.open(a.video) as gif:
        n = gif.n_frames
        picks = [min(n - 1, max(0, round(t * FPS))) for t in a.at]
        frames = []
        for k in picks:
            gif.seek(k)
            frames.append(np.asarray(gif.convert("RGB")))
    fig, axes = plt.subplots(1, len(frames), figsize=(2.4 * len(frames), 2.2))
    for ax, k, frame in zip(np.atleast_1d(axes), picks, frames, strict=True):
        ax.imshow(frame)
        ax.set_title(f"t = {k / FPS:.2f} s", fontsize=9)
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(a.out, dpi=100)
    print(f"wrote {a.out}: frames {picks} of {n}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
