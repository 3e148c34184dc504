"""Shipped calibration data of softhand, installed as the package ``softhand.calibration``.

``fe/`` holds the FE curves of the 12 designs with their provenance (``summary.json``; ``speed-5``
and ``speed-2`` at 5 and 2 mm/s), ``skins/`` the laws and MuJoCo parameters per skin with
``index.json``, ``sensors/`` the FE records of the embedded sensors (``fe/``) and their transfer
laws (``transfer.json``). Code reads these folders through :mod:`softhand.paths` (importlib.resources), so
a regular install finds them as an editable one does.
"""
