"""The visualisation stage of softhand: rerun recordings and pictures of the handshake scene.

The recording and the pictures take their frames as plain arrays; `record` alone runs an
env's episode (softhand.envs.run, imported when it is called), the stage before this one.

- recording: a rerun ``.rrd`` recording of a handshake (both hands, region forces coloured on the
  skin, contacts, skin designs, partner phase), and a summary of a saved recording for tests.
- episode: `record`, any policy's episode of the env recorded to rerun.
- render: PNG pictures and contact sheets (the picture itself: softhand.envs.picture).
- population: the population's Fig. 4-style figure.
"""

from softhand.viz.episode import record
from softhand.viz.recording import (
    HandshakeFrames,
    force_colors,
    read_recording_summary,
    record_handshake,
)

__all__ = [
    "HandshakeFrames",
    "force_colors",
    "read_recording_summary",
    "record",
    "record_handshake",
]
