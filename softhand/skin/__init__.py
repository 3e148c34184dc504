"""Stage 3: skin laws inside MuJoCo.

Representations (rigid contact, calibrated soft contact, soft contact with a relaxation pad, flex
pad), the single-pad rig and the three-link finger they are checked in, the calibration of every
shipped skin (``softhand calibrate``). Imports stages 1-2 (fem, laws) only.
"""
