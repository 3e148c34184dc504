"""The ``softhand`` command line.

``softhand fe indent DESIGN``   one FE indentation (``--json`` for machine-readable output)
``softhand fe sweep``           all 12 designs, curves + summary + plot into calibration/fe
``softhand fe export DESIGN``   an Abaqus or CalculiX input deck of the same model
``softhand calibrate [SKIN ...]``  laws + MuJoCo parameters per skin into calibration/skins
``softhand skin apply HAND OUT``  calibrated skin on named geoms of any MJCF hand, as MJCF
``softhand skin flex-press``    a flex pad on one prosthetic phalanx: force, contact area, pressure
``softhand handshake``          one handshake with shipped calibration: region forces, rerun recording
``softhand render OUT.png``     a picture of the handshake (offscreen mujoco.Renderer)
``softhand bench fe``           speed against error of the FE stage, written to a report
``softhand bench calibration``  error against FE and cost per step of each MuJoCo representation
``softhand bench handshake``    handshake speed and the skins side by side
``softhand bench flex``         the flex region on the hand against the flex rig and the FE
``softhand bench sensors``      embedded sensors: the design table, transfer curves, the handshake
``softhand sensors calibrate``  FE sensor records and transfer laws per design and placement
``softhand materials``         the material library with the source of every number
``softhand design search``     the design search: optuna over pockets, layers and materials, 2D screen, 3D check, STL
``softhand design samplers``   multivariate TPE against NSGA-II on one budget (a report)

Every argument and input file is checked before any work starts. Exit status:

== ===================================================================================
0  done
1  internal error (one line; ``SOFTHAND_TRACEBACK=1`` shows the traceback)
2  bad input: one line ``error: ...`` naming the flag (or file, skin and key), the value and
   the allowed range; nothing computed, nothing written
3  an FE run or a calibration did not converge, or a handshake diverged (what finished is
   written)
4  an output could not be written during the run (a full disk): one line saying what was kept
130 interrupted by Ctrl-C or SIGTERM: what had finished is written (atomically), nothing partial
== ===================================================================================

Default folders come from `softhand.paths` (the same for every command). Only ``fe sweep``,
``fe indent --out``, ``calibrate`` and ``sensors calibrate`` write into the shipped
``calibration/``, and only with ``--force``: the new set goes into a copy beside it that replaces
it only when the run completes (`softhand.io.staged_folder`).
"""

from __future__ import annotations

from softhand.cli import (  # noqa: F401
    bench,
    calibrate,
    design,
    fe,
    handshake,
    materials,
    population,
    sensors,
    skin,
)
from softhand.cli.app import (
    EXIT_CONVERGENCE,
    EXIT_INTERRUPTED,
    EXIT_WRITE,
    Stopped,
    _one_line_warning,
    _Softhand,
    _warnings_summarised,
    main,
    run,
)

__all__ = ["EXIT_CONVERGENCE", "EXIT_INTERRUPTED", "EXIT_WRITE", "Stopped", "_Softhand",
           "_one_line_warning", "_warnings_summarised", "main", "run"]
