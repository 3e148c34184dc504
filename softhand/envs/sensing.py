"""The embedded sensor of every sensing region of the prosthetic hand.

Each of the 18 regions carries one sensor under its skin. Its placement (``bone``, ``interface``
or ``pocket-floor``; `softhand.fem.sensors.PLACEMENTS`) is chosen per region; the default,
``interface`` (under the 0.8 mm outer layer), exists in every design and is where the paper's
conclusion puts sensors a stiff outer layer protects. A region whose skin has no FE model
(``rigid``, a reference skin) has an ideal ``surface`` sensor: its transfer is the identity and the
electronics follow. The reading is the transfer law (`softhand.sensors.transfer`, shipped
in ``calibration/sensors/transfer.json``) of the region's contact force, then the sensor's
electronics (`softhand.sensors.device`).
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import lru_cache
from pathlib import Path

from softhand.fem.geometry import DESIGNS
from softhand.fem.sensors import PLACEMENTS
from softhand.paths import SENSORS_DIR
from softhand.sensors.calibrate import load_transfer_laws
from softhand.sensors.transfer import TransferLaw

__all__ = ["DEFAULT_PLACEMENT", "SURFACE", "parse_placements", "region_laws"]

DEFAULT_PLACEMENT = "interface"
SURFACE = "surface"  # an ideal sensor on the surface of a skin without FE model


@lru_cache(maxsize=8)
def _laws(path: str) -> dict[tuple[str, str], TransferLaw]:
    return load_transfer_laws(path)


def transfer_path(sensor_dir: str | Path | None) -> Path:
    return Path(sensor_dir or SENSORS_DIR) / "transfer.json"


def parse_placements(regions: tuple[str, ...], placement: str | Mapping[str, str] | None
                     ) -> dict[str, str]:
    """Region -> placement: one placement for every region, or a mapping of overrides.

    Raises:
        ValueError: an unknown placement or region, naming it and the allowed values.
    """
    out = dict.fromkeys(regions, DEFAULT_PLACEMENT)
    if placement is None:
        return out
    items = placement.items() if isinstance(placement, Mapping) else \
        [(r, placement) for r in regions]
    for region, p in items:
        if region not in out:
            raise ValueError(f"sensor region {region!r} is unknown; allowed: {', '.join(regions)}")
        if p not in PLACEMENTS:
            raise ValueError(f"sensor placement {p!r} for region {region} is unknown; allowed: "
                             f"{', '.join(PLACEMENTS)}")
        out[region] = p
    return out


def region_laws(skins: Mapping[str, str], placements: Mapping[str, str],
                sensor_dir: str | Path | None = None
                ) -> tuple[list[TransferLaw | None], dict[str, str]]:
    """Per region its transfer law (None: an ideal surface sensor) and its effective placement.

    Raises:
        ValueError: a pocket-floor sensor under a design without a pocket, or a transfer-law
            file that is missing or malformed, naming the region, the design or the key.
    """
    path = transfer_path(sensor_dir)
    laws, used = [], {}
    needed = [r for r in skins if skins[r] in DESIGNS]
    table = _laws(str(path)) if needed else {}
    for region, skin in skins.items():
        p = placements[region]
        if skin not in DESIGNS:
            laws.append(None)
            used[region] = SURFACE
            continue
        law = table.get((skin, p))
        if law is None:
            have = sorted(q for d, q in table if d == skin)
            why = " (it has no pocket)" if p == "pocket-floor" and "pocket" not in skin else ""
            if not have:  # the file lacks the design altogether
                designs = sorted({d for d, _ in table})
                raise ValueError(f"sensor placement {p!r} for region {region}: {path} has no "
                                 f"transfer law for {skin} at any placement (it has "
                                 f"{', '.join(designs) or 'none'}): run `softhand sensors "
                                 f"calibrate` for {skin}, or give the region a skin it has")
            raise ValueError(f"sensor placement {p!r} for region {region}: {path} has no "
                             f"transfer law for {skin}{why}; allowed: {', '.join(have)}")
        laws.append(law)
        used[region] = p
    return laws, used
