"""Skins on the handshake scene: which design each region wears, and the contact pairs that carry it.

Every prosthetic skin region meets every partner tissue geom through an explicit ``<pair>``; its law
is the series combination of the region's skin and the partner's human tissue (both indent: the
indentation of the pair is the sum of the two at the same force), fitted as one calibrated soft
contact and scaled by the pair's inverse inertia (:mod:`softhand.skin.soft_contact`). A ``rigid``
region leaves only the tissue's compliance. Laws come from the shipped calibration files; no FE run.

Where the prosthetic hand has no skin region but meets the partner in a handshake, its rigid shell
(the bone geom) meets every tissue geom through a pair with the ``rigid`` law (:data:`SHELL_BONES`:
the thenar under the thumb's metacarpal and the radial and ulnar borders of the palm). Without
them the partner's tissue would pass through the shell until bone met bone.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from pathlib import Path

import mujoco
import numpy as np

from softhand.hands import partner_tissue_geoms, regions
from softhand.hands.prosthetic import paper_regions
from softhand.laws.references import DATA_MAX_N, HUMAN, PROSTHETIC
from softhand.skin.calibrate import CALIBRATION_MASS_KG, MASS_FACTORS, skin_names
from softhand.skin.files import SKINS_DIR, load_calibration
from softhand.skin.rig import pair_law_values
from softhand.skin.soft_contact import SoftContactParams, fit_soft_contact

__all__ = ["DEFAULT_DESIGN", "SHELL_BONES", "SKIN_CHOICES", "add_skin_pairs",
           "calibrated_max_force", "parse_skins", "series_law",
           "write_skin_laws"]

#: Prosthetic bones without a skin region whose shell meets the partner's tissue in a handshake.
SHELL_BONES = ("thumb_metacarpal", "index_metacarpal", "little_metacarpal")
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
    """Add one pair per (prosthetic skin region, partner tissue geom) and per (shell bone, tissue
    geom); return their names (``{Region}__{tissue}``, ``shell_{bone}__{tissue}``)."""
    tissues = partner_tissue_geoms(spec, hum)
    geoms = {info.region: info.geom for info in regions(spec, pro).values()}
    for bone in SHELL_BONES:
        geoms[f"shell_{bone}"] = f"{pro}bone_{bone}"
        if spec.geom(geoms[f"shell_{bone}"]) is None:
            raise ValueError(f"prosthetic bone geom {geoms[f'shell_{bone}']!r} not found")
    names = []
    for key, geom in geoms.items():
        for tissue in tissues:
            name = f"{key}__{tissue}"
            spec.add_pair(name=name, geomname1=geom, geomname2=tissue, condim=3,
                          friction=[1.0, 1.0, 0.005, 0.0001, 0.0001])
            names.append(name)
    return names


@functools.lru_cache(maxsize=32)
def _soft(skin: str, directory: str) -> SoftContactParams:
    return load_calibration(skin, directory, require=("soft-contact",)).soft_contact


@functools.lru_cache(maxsize=32)
def series_law(skin: str, directory: str = str(SKINS_DIR)) -> SoftContactParams:
    """The pair law of ``skin`` against human tissue (``rigid``: the tissue alone)."""
    tissue = _soft(HUMAN, directory)
    if skin == "rigid":
        return tissue
    own = _soft(skin, directory)
    f = np.linspace(0.0, 2.5, 120)[1:]
    d_skin = _invert(own, f)
    d_tissue = _invert(tissue, f)
    law, _, _ = fit_soft_contact(np.concatenate([[0.0], d_skin + d_tissue]),
                              np.concatenate([[0.0], f]), initial=tissue if skin == PROSTHETIC
                              else own, reference_mass_kg=CALIBRATION_MASS_KG * MASS_FACTORS[0])
    return law


@functools.lru_cache(maxsize=32)
def calibrated_max_force(skin: str, directory: str = str(SKINS_DIR)) -> float:
    """Largest normal force (N) of the data behind ``skin``'s pair law against human tissue.

    The pair law is the skin in series with the tissue, so it is calibrated up to the smaller of
    the two laws' data ranges: a design's fitted range (the end of its elastic law, where the FE
    curves stop, about 2 N), a reference skin's measurements (:data:`DATA_MAX_N`: human tissue
    2 N). ``rigid``: the tissue's range.
    """
    def top(name: str) -> float:
        if name in DATA_MAX_N:  # reference skins: the paper's measurements
            return DATA_MAX_N[name]
        elastic = load_calibration(name, directory).law.elastic
        return float(elastic.force(elastic.max_mm))

    tissue = top(HUMAN)
    return tissue if skin == "rigid" else min(tissue, top(skin))


def _invert(params: SoftContactParams, force_N: np.ndarray) -> np.ndarray:
    """Indentation (mm) at each force of a monotone soft-contact law (dense table)."""
    d = np.linspace(0.0, 20.0, 20001)
    f = params.force(d)
    return np.interp(force_N, f, d)


def write_skin_laws(spec: mujoco.MjSpec, skins: Mapping[str, str], *,
                    directory: str | Path = SKINS_DIR, pro: str = "pro_") -> list[str]:
    """Add the skin pairs (:func:`add_skin_pairs`) to ``spec`` with each region's pair law in
    their ``solref``/``solimp``; shell pairs get the ``rigid`` law (the tissue alone).

    The laws are written into the spec before the caller compiles it, so the MJCF of the spec
    (``spec.to_xml()``, ``models/mjcf/handshake_scene.xml``) is the simulated model. The pair's
    inverse inertia that scales each law is read from one compile of the spec with the pairs.

    Returns:
        The pair names.
    """
    names = add_skin_pairs(spec, pro=pro)
    model = spec.compile()
    for name in names:
        region = name.partition("__")[0]
        skin = skins.get(region, "rigid")
        pair = spec.pair(name)
        pair.solref, pair.solimp = pair_law_values(model, name, series_law(skin, str(directory)))
    return names
