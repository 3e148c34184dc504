"""Skins on the handshake scene: which design each region wears, and the contact pairs that carry it.

Every prosthetic skin geom meets every partner tissue geom through an explicit ``<pair>``; its law
is the series combination of the region's skin and the partner's human tissue (both indent: the
indentation of the pair is the sum of the two at the same force), shipped as each skin's
``pair_law`` (:mod:`softhand.skin.pair`, fitted over 0-20 N by ``softhand calibrate``) and scaled
by the pair's inverse inertia (:mod:`softhand.skin.soft_contact`). A ``rigid`` region leaves only
the tissue's compliance. Laws come from the shipped calibration files; no FE run, no refit.

The prosthetic hand's skin covers its whole envelope (:mod:`softhand.hands.envelope`): besides the
18 sensing regions, the non-sensing thenar skin (:data:`softhand.hands.prosthetic.UNSENSED_SKINS`)
wears the design of the region it belongs to, and has its pairs too. No bare shell meets the
partner: every pair is a skin (or a ``rigid`` region) against tissue.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from pathlib import Path

import mujoco

from softhand.hands import partner_tissue_geoms, regions
from softhand.hands.prosthetic import UNSENSED_SKINS, paper_regions
from softhand.laws.references import DATA_MAX_N, HUMAN
from softhand.skin.calibrate import skin_names
from softhand.skin.files import SKINS_DIR, load_calibration
from softhand.skin.rig import pair_law_values
from softhand.skin.soft_contact import SoftContactParams

__all__ = ["DEFAULT_DESIGN", "SKIN_CHOICES", "CalibratedRangeWarning", "add_skin_pairs", "calibrated_max_force",
           "parse_skins", "series_law", "skin_of_pair", "write_skin_laws"]

class CalibratedRangeWarning(UserWarning):
    """A contact between the hands carried more force than its pair law was calibrated to (the
    force above the range is an extrapolation of the law); raised once per pair and episode."""


DEFAULT_DESIGN = "pocket2-sil"  # the most lifelike design (calibration/skins/index.json ranking)
SKIN_CHOICES = (*[n for n in skin_names() if n != HUMAN], "rigid")


def parse_skins(design: str | None = None, overrides: Mapping[str, str] | None = None
                ) -> dict[str, str]:
    """Region -> skin: ``design`` everywhere (default the most lifelike), then ``overrides``.

    Raises:
        ValueError: an unknown region or skin, naming it and the allowed values.
    """
    names = paper_regions()
    design = design or DEFAULT_DESIGN
    if design not in SKIN_CHOICES:
        raise ValueError(f"skin design {design!r} is unknown; allowed: {', '.join(SKIN_CHOICES)}")
    out = dict.fromkeys(names, design)
    for region, skin in (overrides or {}).items():
        if region not in out:
            raise ValueError(f"region {region!r} is unknown; allowed: {', '.join(names)}")
        if skin not in SKIN_CHOICES:
            raise ValueError(f"skin {skin!r} for region {region} is unknown; allowed: "
                             f"{', '.join(SKIN_CHOICES)}")
        out[region] = skin
    return out


def add_skin_pairs(spec: mujoco.MjSpec, *, pro: str = "pro_", hum: str = "hum_") -> list[str]:
    """Add one pair per (prosthetic skin geom, partner tissue geom); return their names,
    ``{Skin}__{tissue}`` with Skin a region (``Index1``) or a non-sensing skin (``Thenar``)."""
    tissues = partner_tissue_geoms(spec, hum)
    geoms = {info.region: info.geom for info in regions(spec, pro).values()}
    for name in UNSENSED_SKINS:
        geoms[name] = f"{pro}skin_{name}"
        if spec.geom(geoms[name]) is None:
            raise ValueError(f"prosthetic skin geom {geoms[name]!r} not found")
    names = []
    for key, geom in geoms.items():
        for tissue in tissues:
            name = f"{key}__{tissue}"
            spec.add_pair(name=name, geomname1=geom, geomname2=tissue, condim=3,
                          friction=[1.0, 1.0, 0.005, 0.0001, 0.0001])
            names.append(name)
    return names


def skin_of_pair(pair: str, skins: Mapping[str, str]) -> tuple[str, str]:
    """(skin geom key, design) of a pair name made by :func:`add_skin_pairs`: a region's own
    design, or for a non-sensing skin the design of the region it belongs to."""
    key = pair.partition("__")[0]
    if key in UNSENSED_SKINS:
        return key, skins.get(UNSENSED_SKINS[key][1], "rigid")
    return key, skins.get(key, "rigid")


@functools.lru_cache(maxsize=32)
def _calibration(skin: str, directory: str):
    return load_calibration(skin, directory, require=("soft-contact",))


@functools.lru_cache(maxsize=32)
def series_law(skin: str, directory: str = str(SKINS_DIR)) -> SoftContactParams:
    """The pair law of ``skin`` against human tissue: the shipped ``pair_law`` of its calibration
    (:mod:`softhand.skin.pair`: the two laws in series, fitted over the whole 0-20 N range);
    ``rigid``: the tissue's own soft contact (only the tissue indents).

    Raises:
        ValueError: a calibration file without a pair law (written before they existed).
    """
    if skin == "rigid":
        return _calibration(HUMAN, directory).soft_contact
    cal = _calibration(skin, directory)
    if cal.pair_law is None:
        raise ValueError(f"calibration of skin {skin!r} in {directory} has no pair_law (the law "
                         f"against human tissue): run `softhand calibrate {skin}`")
    return cal.pair_law.params


@functools.lru_cache(maxsize=32)
def calibrated_max_force(skin: str, directory: str = str(SKINS_DIR)) -> float:
    """Largest normal force (N) up to which ``skin``'s pair law against human tissue is calibrated:
    the smaller of the two laws' data ranges (a design's FE curves, 20 N; the tissue's published
    data, :data:`DATA_MAX_N`, 7 N). ``rigid``: the tissue's range."""
    if skin == "rigid":
        return float(DATA_MAX_N[HUMAN])
    series_law(skin, directory)  # checks the file has a pair law
    return float(_calibration(skin, directory).pair_law.calibrated_max_N)


def write_skin_laws(spec: mujoco.MjSpec, skins: Mapping[str, str], *,
                    directory: str | Path = SKINS_DIR, pro: str = "pro_") -> list[str]:
    """Add the skin pairs (:func:`add_skin_pairs`) to ``spec`` with each region's pair law in
    their ``solref``/``solimp`` (a non-sensing skin: its region's design).

    The laws are written into the spec before the caller compiles it, so the MJCF of the spec
    (``spec.to_xml()``, ``models/mjcf/handshake_scene.xml``) is the simulated model. The pair's
    inverse inertia that scales each law is read from one compile of the spec with the pairs.

    Returns:
        The pair names.
    """
    names = add_skin_pairs(spec, pro=pro)
    model = spec.compile()
    for name in names:
        _, skin = skin_of_pair(name, skins)
        pair = spec.pair(name)
        pair.solref, pair.solimp = pair_law_values(model, name, series_law(skin, str(directory)))
    return names
