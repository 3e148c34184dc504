"""The visualisation stage of softhand: rerun recordings of the handshake scene.

May import softhand.hands and the stages before it (softhand.paper, softhand.laws, softhand.fem,
softhand.skin), never softhand.envs: callers hand their frames to this stage as plain arrays.

- recording: a rerun ``.rrd`` recording of a handshake (both hands, region forces coloured on the
  skin, contacts, skin designs, partner phase), and a summary of a saved recording for tests.
"""

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
    "record_handshake",
]
