"""softhand: lifelike prosthetic skins, from FE indentation to a MuJoCo handshake.

Stages (each imports only the ones before it):

1. `softhand.fem` - FE indentation of the paper's synthetic phalanges.
"""

__version__ = "0.1.0"
