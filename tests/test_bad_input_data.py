"""Validate first, work after: every bad input is one ValueError naming the key, value and range.

One test per class of input (material constants, geometry overrides, FE curve CSV files,
calibration JSON files, the handshake env), each with exact message fragments, plus a check that
valid input still loads.
"""

from __future__ import annotations

import copy
import json
import math
import shutil

import numpy as np
import pytest

from softhand.fem.assembly import Assembler
from softhand.fem.geometry import GEOMETRY_RANGES, PhalanxGeometry, parse_design
from softhand.fem.materials import check_materials, material
from softhand.fem.mesh import MESH_LEVELS, build_mesh
from softhand.laws.fit import load_curve
from softhand.skin.files import SKINS_DIR, load_calibration

NAN, INF = math.nan, math.inf

# --- 1. material constants ------------------------------------------------------------------


@pytest.mark.parametrize("constants,needles", [
    ({"mu_MPa": 0.1}, ["sil.mu_MPa = 0.1: expected a list of 2 numbers"]),
    ({"mu_MPa": "abc"}, ["sil.mu_MPa = 'abc': expected a list of 2 numbers"]),
    ({"mu_MPa": [0.1]}, ["sil.mu_MPa = [0.1]: expected a list of 2 numbers (got 1)"]),
    ({"mu_MPa": [0.1, 0.2, 0.3], "alpha": [1.0, 2.0]},
     ["sil.mu_MPa = [0.1, 0.2, 0.3]: expected a list of 2 numbers", "as many as sil.alpha"]),
    ({"nu": [0.4]}, ["sil.nu = [0.4]: expected a finite number in (0, 0.5)"]),
    ({"nu": "0.4"}, ["sil.nu = '0.4': expected a finite number in (0, 0.5)"]),
    ({"nu": True}, ["sil.nu = True: expected a finite number in (0, 0.5)"]),
    ({"nu": NAN}, ["sil.nu = nan: expected a finite number in (0, 0.5)"]),
    ({"nu": 0.5}, ["sil.nu = 0.5: expected a finite number in (0, 0.5)"]),
    ({"nu": 0.0}, ["sil.nu = 0.0: expected a finite number in (0, 0.5)"]),
    ({"mu_MPa": [0.08, INF]}, ["sil.mu_MPa[1] = inf: expected a finite number > 0"]),
    ({"mu_MPa": [0.0, 0.01]}, ["sil.mu_MPa[0] = 0.0: expected a finite number > 0"]),
    ({"mu_MPa": [0.08, "x"]}, ["sil.mu_MPa[1] = 'x': expected a finite number > 0"]),
    ({"alpha": [0.0, 15.5]}, ["sil.alpha[0] = 0.0: expected a finite non-zero number"]),
    ({"alpha": [NAN, 15.5]}, ["sil.alpha[0] = nan: expected a finite number"]),
    ({"g": [1.0, 0.0, 0.0]}, ["sil.g[0] = 1.0: expected a finite number in [0, 1)"]),
    ({"g": [-0.1, 0.0, 0.0]}, ["sil.g[0] = -0.1: expected a finite number in [0, 1)"]),
    ({"g": [0.5, 0.3, 0.2]}, ["sil.g = [0.5, 0.3, 0.2]: the sum 1 must be < 1",
                              "allowed range [0, 1)"]),
    ({"g": [0.1], "tau_s": [1.0, 2.0]}, ["sil.g = [0.1]: expected a list of 2 numbers (got 1)"]),
    ({"tau_s": [0.025, 0.0, 0.3]}, ["sil.tau_s[1] = 0.0: expected a finite number > 0"]),
    ({"tau_s": [0.025, -1.0, 0.3]}, ["sil.tau_s[1] = -1.0: expected a finite number > 0"]),
    ({"mu": [0.1, 0.01]}, ["sil.mu = [0.1, 0.01]: unknown key; allowed: nu, mu_MPa, alpha, g, "
                           "tau_s"]),
    (5, ["sil = 5: expected an object with keys nu, mu_MPa, alpha, g, tau_s"]),
    ([0.49], ["sil = [0.49]: expected an object"]),
])
def test_bad_material_constants_name_the_key_value_and_range(constants, needles):
    with pytest.raises(ValueError) as info:
        material("sil", constants=constants)
    for needle in needles:
        assert needle in str(info.value)
    with pytest.raises(ValueError) as info:
        check_materials({"sil": constants})
    assert needles[0] in str(info.value)


def test_materials_file_top_level_and_valid_constants():
    for data, needle in (([1], "top level = [1]: expected an object with keys sil, pu"),
                         ({"silicone": {}}, "silicone = {}: unknown key; allowed: sil, pu"),
                         ("sil", "top level = 'sil': expected an object")):
        with pytest.raises(ValueError, match=None) as info:
            check_materials(data)
        assert needle in str(info.value)
    good = {"sil": {"nu": 0.45, "mu_MPa": [0.1, 0.02, 0.01], "alpha": [0.5, 2.0, 10.0]},
            "pu": {"g": [], "tau_s": []}}
    assert check_materials(good) == good
    sil = material("sil", constants=good["sil"], moduli="instantaneous")
    assert sil.hyperfoam.mu == (0.1, 0.02, 0.01) and sil.hyperfoam.nu == 0.45
    assert material("pu", constants=good["pu"]).n_terms == 0
    assert material("sil").hyperfoam == material("sil", constants={}).hyperfoam


# --- 2. geometry overrides ------------------------------------------------------------------


@pytest.mark.parametrize("design,overrides,needles", [
    ("pocket2-sil", {"pocket_height_mm": -1.0},
     ["pocket_height_mm = -1.0: expected a finite number in [0, 6]"]),
    ("pocket2-sil", {"height_mm": 1e6}, ["height_mm = 1000000.0: expected a finite number in [6, 12]"]),
    ("pocket2-sil", {"height_mm": 0.0}, ["height_mm = 0.0: expected a finite number in [6, 12]"]),
    ("pocket2-sil", {"width_mm": NAN}, ["width_mm = nan: expected a finite number in [12, 20]"]),
    ("pocket2-sil", {"length_mm": INF}, ["length_mm = inf: expected a finite number in [5, 60]"]),
    ("pocket2-sil", {"outer_layer_mm": -0.8},
     ["outer_layer_mm = -0.8: expected a finite number in [0.2, 2]"]),
    ("pocket2-sil", {"pocket_roof_mm": "1.4"},
     ["pocket_roof_mm = '1.4': expected a finite number in [0.5, 3]"]),
    ("pocket2-sil", {"profile_exponent": 1.5},
     ["profile_exponent = 1.5: expected a finite number in [2, 3]"]),
    ("pocket2-sil", {"outer_layer_mm": 1.5},
     ["outer_layer_mm = 1.5: must be thinner than pocket_roof_mm = 1.4",
      "allowed range [0.2, 1.4)"]),
    ("pocket2-sil", {"pocket_height_mm": 5.0},
     ["pocket_height_mm = 5.0: allowed range [0.25, 2.93) at pocket_roof_mm = 1.4, width_mm = 16, "
      "height_mm = 9"]),
    ("pocket2-sil", {"pocket_height_mm": 0.1},
     ["pocket_height_mm = 0.1: expected 0 (no pocket) or a pocket of at least 0.25 mm"]),
    ("pocket1-sil", {"pocket_roof_mm": 3.0},
     ["pocket_roof_mm = 3.0: allowed range (0.8, 2.33) at width_mm = 16"]),
    ("pocket2-sil", {"pocket_half_width_mm": 9.0},
     ["pocket_half_width_mm = 9.0: allowed range [0.5, 6.1] at width_mm = 16 and pocket_roof_mm"]),
    ("pocket2-sil", {"width_mm": 12.0, "height_mm": 12.0},
     ["width_mm = 12, height_mm = 12, profile_exponent = 2: the profile's smallest radius of "
      "curvature is 3 mm"]),
    ("solid-sil", {"pocket_height_mm": 2.0},
     ["pocket_height_mm = 2.0: design solid-sil has no pocket;", "pocket2-sil"]),
    ("solid-pu-sil", {"pocket_half_width_mm": 4.0},
     ["pocket_half_width_mm = 4.0: design solid-pu-sil has no pocket;", "pocket1-pu"]),
    ("pocket2-sil", {"nonsense": 1.0},
     ["geometry field nonsense = 1.0 is unknown; allowed: width_mm, height_mm"]),
])
def test_bad_geometry_names_the_field_value_and_range(design, overrides, needles):
    with pytest.raises(ValueError) as info:
        parse_design(design).geometry(**overrides)
    for needle in needles:
        assert needle in str(info.value)


def _largest(fields: dict, key: str, lo: float, hi: float) -> float:
    """Largest value of ``key`` in [lo, hi] that validation accepts (bisection)."""
    def ok(v: float) -> bool:
        try:
            PhalanxGeometry(**{**fields, key: v})
            return True
        except ValueError:
            return False
    assert ok(lo)
    if ok(hi):
        return hi
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if ok(mid) else (lo, mid)
    return lo


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("shape", [(12, 6, 2.0), (20, 9, 2.5), (16, 9, 3.0), (20, 12, 3.0),
                                   (20, 9, 2.0)])
def test_geometry_at_the_bounds_meshes_with_positive_det_j(shape, dim):
    """Geometries just inside the allowed ranges build a coarse mesh and an Assembler (det J > 0).

    The shapes are range corners where the curvature limit binds (found by scanning every corner
    of the ranges on all four mesh levels in 2D and the coarse level in 3D).
    """
    width, height, n = shape
    base = dict(width_mm=width, height_mm=height, profile_exponent=n, length_mm=5.0,
                outer_layer_mm=0.2, pocket_height_mm=0.0, pocket_roof_mm=0.5,
                pocket_half_width_mm=0.5)
    roof = _largest(base, "pocket_roof_mm", 0.5, GEOMETRY_RANGES["pocket_roof_mm"][1])
    deepest_pocket = {**base, "pocket_height_mm": _largest(base, "pocket_height_mm", 0.25, 6.0)}
    candidates = [{**base, "pocket_roof_mm": roof, "outer_layer_mm": min(2.0, roof * 0.999)},
                  {**base, "pocket_roof_mm": roof, "pocket_height_mm": 1.0},
                  deepest_pocket]
    for fields in candidates:
        fields["pocket_half_width_mm"] = _largest(fields, "pocket_half_width_mm", 0.5, 9.5)
        geom = PhalanxGeometry(**fields)
        mesh = build_mesh(geom, MESH_LEVELS["coarse"], dim=dim)
        asm = Assembler(mesh, [material("sil"), material("pu")], threads=1)
        assert np.all(asm.wdet > 0), fields


def test_valid_geometry_overrides_still_load():
    g = parse_design("pocket2-sil").geometry(pocket_roof_mm=1.5, height_mm=10.0, width_mm=18.0)
    assert (g.pocket_roof_mm, g.height_mm, g.width_mm, g.pocket_height_mm) == (1.5, 10.0, 18.0, 2.0)
    assert parse_design("solid-sil").geometry(pocket_height_mm=0.0).pocket_height_mm == 0.0
    # a narrow solid design: its contact-zone edge moves in to fit (it has no pocket to move)
    assert parse_design("solid-sil").geometry(width_mm=15.0).pocket_half_width_mm == 5.0
    narrow = parse_design("solid-sil").geometry(width_mm=13.0, height_mm=6.0, pocket_roof_mm=1.1)
    assert narrow.pocket_half_width_mm == pytest.approx(4.9)
    assert parse_design("pocket1-pu").geometry() == PhalanxGeometry(pocket_height_mm=1.0)


# --- 3. FE curve CSV files ------------------------------------------------------------------

HEADER = "time_s,displacement_mm,force_N,hold\n"
GOOD_ROWS = "0,0,0,0\n0.04,0.02,0.0036,0\n0.08,0.04,0.0075,0\n1.0,0.04,0.007,1\n"


@pytest.mark.parametrize("content,needle", [
    (b"", "the file is empty; expected the header time_s,displacement_mm,force_N,hold"),
    (b"\n\n", "the file is empty"),
    (HEADER.encode(), "0 data rows; at least 3 are needed"),
    ((HEADER + "0,0,0,0\n0.04,0.02,0.00").encode(),
     "line 3: 3 cells '0.04,0.02,0.00', expected 4 (time_s,displacement_mm,force_N,hold): "
     "truncated"),
    ((HEADER + "0,0,0,0\n0.04,0.02,0.0036,\n").encode(),
     "line 3, column hold: '' is not a number"),
    (("time,displacement_mm,force_N,hold\n" + GOOD_ROWS).encode(),
     "line 1: header 'time,displacement_mm,force_N,hold' is not the FE curve header "
     "time_s,displacement_mm,force_N,hold (missing time_s; unknown 'time')"),
    (GOOD_ROWS.encode(), "line 1: header '0,0,0,0' is not the FE curve header"),
    ((HEADER + "0,0,0,0\n0.04,abc,0.0036,0\n0.08,0.04,0.0075,0\n").encode(),
     "line 3, column displacement_mm: 'abc' is not a number"),
    ((HEADER + "0,0,0,0\n0.04,0.02,nan,0\n0.08,0.04,0.0075,0\n").encode(),
     "line 3, column force_N: 'nan': expected a finite number"),
    ((HEADER + "0,0,0,0\n0.04,0.02,0.0036,0\n0.04,0.04,0.0075,0\n").encode(),
     "line 4, column time_s: '0.04': time must increase (previous row 0.04)"),
    ((HEADER + "0,0,0,0\n0.04,0.02,0.0036,0.5\n0.08,0.04,0.0075,0\n").encode(),
     "line 3, column hold: '0.5': expected 0 (ramp) or 1 (hold)"),
    ((HEADER + "0,0,0,0\n\n0.08,0.04,0.0075,0\n").encode(), "line 3: empty row inside the file"),
    ((HEADER + "0,0,0,0\n0.04,0.02,0.0036,0\n0.08,0.01,0.0075,0\n").encode(),
     "ramp displacement is not monotone"),
    (HEADER.encode() + b"0,0,0,0\n0.04,0.02,\xff0.0036,0\n", "line 3: not UTF-8 text (byte 0xff"),
])
def test_bad_curve_file_names_the_file_line_and_column(tmp_path, content, needle):
    path = tmp_path / "pocket2-sil.csv"
    path.write_bytes(content)
    with pytest.raises(ValueError) as info:
        load_curve(path)
    message = str(info.value)
    assert message.startswith(f"{path}: ") and needle in message


def test_valid_curve_files_still_load(tmp_path):
    path = tmp_path / "c.csv"
    path.write_text(HEADER + GOOD_ROWS)
    curve = load_curve(path)
    assert curve.time_s.tolist() == [0.0, 0.04, 0.08, 1.0] and curve.hold.tolist()[-1]
    path.write_text("hold,force_N,displacement_mm,time_s\n0,0,0,0\n0,0.1,0.1,1\n1,0.09,0.1,2")
    assert load_curve(path).force_N.tolist() == [0.0, 0.1, 0.09]  # any column order, no last \n
    shipped = SKINS_DIR.parent / "fe" / "pocket2-sil.csv"
    cal = json.loads((SKINS_DIR / "pocket2-sil.json").read_text())
    assert load_curve(shipped).sha256 == cal["law"]["source"]["curves"]["pocket2-sil@0.5mm/s"]


# --- 4. calibration JSON files --------------------------------------------------------------


def _shipped(name: str = "pocket2-sil") -> dict:
    return json.loads((SKINS_DIR / f"{name}.json").read_text())


def _set(data: dict, path: tuple, value) -> dict:
    data = copy.deepcopy(data)
    node = data
    for k in path[:-1]:
        node = node[k]
    if value is KeyError:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return data


SC = ("representations", "soft-contact", "params")
PAD = ("representations", "soft-contact+relaxation", "params")


@pytest.mark.parametrize("path,value,needle", [
    ((*SC, "solimp", 0), "x",
     "representations.soft-contact.params.solimp[0] = 'x': expected a finite number in "
     "[0.0001, 0.3] (d0)"),
    ((*SC, "solimp", 1), NAN, "representations.soft-contact.params.solimp[1] = nan"),
    ((*SC, "solimp"), [0.1, 0.2], "representations.soft-contact.params.solimp = [0.1, 0.2]: "
                                  "expected a list of 5 numbers (got 2)"),
    ((*SC, "stiffness_N_per_m_per_invmass"), "897",
     "representations.soft-contact.params.stiffness_N_per_m_per_invmass = '897': expected a "
     "finite number in (0, 1e+08]"),
    ((*SC, "stiffness_N_per_m_per_invmass"), 1e300,
     "representations.soft-contact.params.stiffness_N_per_m_per_invmass = 1e+300: expected a "
     "finite number in (0, 1e+08] (beyond it no timestep integrates it stably)"),
    ((*SC, "damping_Ns_per_m_per_invmass"), 2e4,
     "representations.soft-contact.params.damping_Ns_per_m_per_invmass = 20000.0: expected a "
     "finite number in [0, 10000]"),
    ((*SC, "damping_Ns_per_m_per_invmass"), KeyError,
     "representations.soft-contact.params.damping_Ns_per_m_per_invmass: missing (required: "),
    ((*PAD, "damping_scale"), [1.0],
     "representations.soft-contact+relaxation.params.damping_scale = [1.0]: expected a list of 2 "
     "numbers (got 1) (one per Prony term of the law)"),
    ((*PAD, "n_knots"), 2.5,
     "representations.soft-contact+relaxation.params.n_knots = 2.5: expected an integer in [1, 50]"),
    ((*PAD, "pad_mass_kg"), None,
     "representations.soft-contact+relaxation.params.pad_mass_kg = None: expected a finite "
     "number > 0"),
    (("representations", "rigid", "params", "solref"), 0.02,
     "representations.rigid.params.solref = 0.02: expected a list of 2 numbers"),
    (("representations", "rigid", "rms_error_pct_of_2N"), [],
     "representations.rigid.rms_error_pct_of_2N = []: expected a finite number >= 0"),
    (("representations", "flex", "params", "poisson"), 0.6,
     "representations.flex.params: poisson"),
    (("representations", "soft-contact", "representation"), "rigid",
     "representations.soft-contact.representation = 'rigid': expected 'soft-contact'"),
    (("representations", "jelly"), {}, "representations.jelly = {}: unknown key; allowed: rigid"),
    (("law", "prony", "g", 0), "0.05", "law.prony.g[0] = '0.05': expected a finite number in [0, 1)"),
    (("law", "prony", "tau_s"), [0.1], "law.prony.tau_s = [0.1]: expected a list of 2 numbers"),
    (("pair_law", "calibrated_max_N"), 30.0,
     "pair_law.calibrated_max_N = 30.0: expected a finite number in (0, 20] (at most fitted_max_N)"),
    (("pair_law", "against"), 3, "pair_law.against = 3: expected a string"),
    (("law", "prony", "g_inf"), 0.5, "law.prony.g_inf = 0.5: expected 1 - sum(g) = 0.91"),
    (("law", "elastic", "coefficients_N_per_mm", 3), -1.0,
     "law.elastic.coefficients_N_per_mm[3] = -1.0: expected a finite number >= 0"),
    (("law", "elastic", "knots_mm"), KeyError, "law.elastic.knots_mm: missing (required: "),
    (("law", "elastic", "knots_mm", 5), 0.1, "law.elastic: knots must start at 0 and not decrease"),
    (("law", "fitted", 0, "rms_pct_of_2N"), INF,
     "law.fitted[0].rms_pct_of_2N = inf: expected a finite number >= 0"),
    (("law", "name"), 3, "law.name = 3: expected a string"),
    (("law",), KeyError, "law: missing (required: format_version, design, law, representations)"),
    (("design",), "pocket1-sil", "design = 'pocket1-sil': expected 'pocket2-sil' (the file's skin)"),
    (("format_version",), "1", "format_version '1' is not 2"),
    (("provenance",), [], "provenance = []: expected an object"),
])
def test_bad_calibration_file_names_the_file_skin_and_key(tmp_path, path, value, needle):
    (tmp_path / "pocket2-sil.json").write_text(json.dumps(_set(_shipped(), path, value)))
    with pytest.raises(ValueError) as info:
        load_calibration("pocket2-sil", tmp_path)
    message = str(info.value)
    assert message.startswith(f"{tmp_path / 'pocket2-sil.json'}: skin pocket2-sil: "), message
    assert needle in message, message


def test_missing_representation_and_the_env_name_file_skin_and_key(tmp_path):
    from softhand.envs import HandshakeEnv
    from softhand.envs.skins import series_law

    for f in SKINS_DIR.glob("*.json"):
        shutil.copy(f, tmp_path / f.name)
    data = _set(_shipped(), ("representations", "soft-contact"), KeyError)
    (tmp_path / "pocket2-sil.json").write_text(json.dumps(data))
    cal = load_calibration("pocket2-sil", tmp_path)  # the file itself is valid
    with pytest.raises(ValueError, match="skin pocket2-sil: representation 'soft-contact' is not "
                                         "calibrated"):
        _ = cal.soft_contact
    with pytest.raises(ValueError) as info:
        load_calibration("pocket2-sil", tmp_path, require=("soft-contact",))
    assert "pocket2-sil.json: skin pocket2-sil: representations.soft-contact: missing" in \
        str(info.value)
    series_law.cache_clear()
    with pytest.raises(ValueError) as info:
        HandshakeEnv(design="pocket2-sil", calibration_dir=tmp_path)
    assert "pocket2-sil.json: skin pocket2-sil: representations.soft-contact: missing" in \
        str(info.value)
    bad = _set(_shipped(), (*SC, "solimp", 0), "x")
    (tmp_path / "pocket2-sil.json").write_text(json.dumps(bad))
    series_law.cache_clear()
    with pytest.raises(ValueError) as info:
        HandshakeEnv(design="pocket2-sil", calibration_dir=tmp_path)
    assert ("pocket2-sil.json: skin pocket2-sil: representations.soft-contact.params.solimp[0] = "
            "'x': expected a finite number") in str(info.value)
    series_law.cache_clear()


def test_valid_calibration_files_still_load():
    from softhand.skin.files import shipped_skins

    for skin in shipped_skins():
        cal = load_calibration(skin, require=("soft-contact",))
        assert cal.design == skin and cal.soft_contact.stiffness > 0
        if "soft-contact+relaxation" in cal.representations:
            assert len(cal.pad.damping_scale) == len(cal.law.prony.g)


# --- 5. the handshake env -------------------------------------------------------------------


@pytest.fixture(scope="module")
def env():
    from softhand.envs import HandshakeEnv

    return HandshakeEnv(design="rigid")


@pytest.mark.parametrize("kwargs,needle", [
    ({"reward_weights": {"grip": NAN}}, "reward_weights['grip'] = nan: expected a finite number >= 0"),
    ({"reward_weights": {"effort": INF}}, "reward_weights['effort'] = inf: expected a finite number"),
    ({"reward_weights": {"contact": -0.5}}, "reward_weights['contact'] = -0.5: expected a finite "
                                            "number >= 0"),
    ({"reward_weights": {"grip": "1"}}, "reward_weights['grip'] = '1': expected a finite number"),
    ({"reward_weights": [1.0]}, "reward_weights = [1.0]: expected a mapping"),
    ({"timestep_s": 0.01}, "timestep_s = 0.01: expected a finite number in [0.0001, 0.005] s"),
    ({"timestep_s": 1e-7}, "timestep_s = 1e-07: expected a finite number in [0.0001, 0.005] s"),
    ({"timestep_s": NAN}, "timestep_s = nan: expected a finite number in [0.0001, 0.005] s"),
    ({"frame_skip": 0}, "frame_skip = 0: expected an integer in [1, 50] (frame_skip x timestep_s "
                        "<= 0.1 s)"),
    ({"frame_skip": 2.5}, "frame_skip = 2.5: expected an integer in [1, 50]"),
    ({"squeeze": "x"}, "squeeze = 'x': expected a finite number in (0, 5]"),
    ({"overload_N": -1.0}, "overload_N = -1.0: expected a finite number > 0"),
    ({"randomize": "yes"}, "randomize = 'yes': expected True or False"),
])
def test_bad_env_arguments_name_the_argument_value_and_range(kwargs, needle):
    from softhand.envs import HandshakeEnv

    with pytest.raises(ValueError) as info:
        HandshakeEnv(design="rigid", **kwargs)
    assert needle in str(info.value)


@pytest.mark.parametrize("action,needle", [
    (np.zeros(6, complex), "6 finite real values in [-1, 1] (got dtype complex128)"),
    ([1j, 0, 0, 0, 0, 0], "(got dtype complex128)"),
    (["a"] * 6, "(got dtype <U1)"),
    ([0, 0, 0, 0, 0, None], "(got dtype object)"),
    (np.zeros(6, bool), "(got dtype bool)"),
    (np.zeros(5), "6 finite values in [-1, 1] (got shape (5,))"),
    (np.zeros((1, 6)), "(got shape (1, 6))"),
    ([np.nan, 0, 0, 0, 0, 0], "action [nan  0.  0.  0.  0.  0.] is outside the action space"),
    ([0, 0, np.inf, 0, 0, 0], "is outside the action space: 6 finite values in [-1, 1]"),
    ([2.0, 0, 0, 0, 0, 0], "action [2. 0. 0. 0. 0. 0.] is outside the action space"),
    # shown as given: it was printed "1.", which looks allowed
    ([1.0001, 0, 0, 0, 0, 0], "action [1.0001 0.     0.     0.     0.     0.    ] is outside"),
])
def test_bad_actions_and_seeds_are_refused(env, action, needle):
    env.reset(seed=0)
    with pytest.raises(ValueError) as info:
        env.step(action)
    assert needle in str(info.value)
    for seed in (-1, 1.5, "3", True):
        with pytest.raises(ValueError, match=f"seed = {seed!r}: expected None or an integer >= 0"):
            env.reset(seed=seed)
    with pytest.raises(ValueError, match="options key 'fast' is unknown; allowed: grip_N, "
                                         "duration_s, shake_phase_rad"):
        env.reset(seed=0, options={"fast": True})
    for key, value, allowed in (("grip_N", 0.0, r"\[1e-06, 12.5\]"),
                                ("duration_s", 9.0, r"\[2, 6\]"),
                                ("shake_phase_rad", float("nan"), r"\[-6.28319, 6.28319\]")):
        with pytest.raises(ValueError, match=rf"options\['{key}'\] = {value!r}: allowed {allowed}"):
            env.reset(seed=0, options={key: value})


def test_step_after_the_episode_ended_asks_for_reset(env):
    env.reset(seed=2)
    truncated = False
    while not truncated:
        _, _, terminated, truncated, _ = env.step(np.zeros(6, np.float32))
        assert not terminated
    with pytest.raises(RuntimeError, match=r"the episode is over \(truncated at t = 4\.\d+ s\): "
                                           r"call reset\(\) before step\(\)"):
        env.step(np.zeros(6))
    obs, _ = env.reset(seed=np.int64(2))  # numpy integers are seeds too; valid input still works
    assert np.all(np.isfinite(env.step(np.zeros(6))[0])) and obs.shape == env.observation_space.shape
