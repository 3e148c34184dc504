"""The touch env's action and observation, entry by entry: one name with its unit for each.

One source for three readers: the env's ``action_names`` and ``observation_names`` (and the
vector env's ``single_`` ones), the layout tables of ``HandshakeEnv``'s docstring (a test checks
that they are `action_table` and `observation_table`), and the tables of
``docs/controllers.md`` (generated from these at build time).

A name is ``quantity/element [unit]``: ``qpos/pro_index_mcp [rad]``, ``sensor_patch/Index1 [N]``,
``speed/pro_thumb_rot_motor [fraction of max]``; the last observation is ``episode_fraction [-]``.

The observation's region values are chosen by ``observe`` (`OBSERVE`), each a block of the
18 regions in ``region_names`` order (`REGION_BLOCKS`):

* ``sensor_patch``: what each region's embedded sensor reads on its 4 x 4 mm patch under the
  skin, a fraction of the region's load (``info["sensor_readings_N"]``);
* ``load_estimate``: the load a calibrated read-out infers from that reading, the transfer law
  inverted (``info["sensor_load_estimate_N"]``; 0 inside a pocket's dead band);
* ``region_load``: the true normal contact force on the region (``info["region_forces_N"]``).
"""

from __future__ import annotations

import textwrap
from collections.abc import Mapping, Sequence

import numpy as np

from softhand.hands import prosthetic_actuators

__all__ = ["ACTION_UNIT", "OBSERVE", "REGION_BLOCKS", "action_names", "action_rows",
           "action_table", "observation_names", "observation_rows", "observation_table",
           "region_values"]

#: What each 18-value block of the observation holds, per region (N), and where ``info`` has it.
REGION_BLOCKS = {
    "sensor_patch": ("the reading of the region's embedded sensor on its 4 x 4 mm patch, a "
                     "fraction of the region's load", "sensor_readings_N"),
    "load_estimate": ("the load a calibrated read-out infers from that reading, the transfer law "
                      "inverted, 0 inside a pocket's dead band", "sensor_load_estimate_N"),
    "region_load": ("the true normal contact force on the region", "region_forces_N"),
}
#: ``observe`` -> the region blocks the observation carries, in order (the first is the default).
OBSERVE = {"sensor": ("sensor_patch",), "load": ("load_estimate",),
           "contact": ("region_load",), "both": ("sensor_patch", "region_load")}
#: The unit of an action: the motor's speed as a fraction of its maximum (positive closes).
ACTION_UNIT = "fraction of max"
#: What each motor does (ctrl order, softhand.hands.prosthetic_actuators).
_MOTORS = ("index finger", "middle finger", "ring finger", "little finger", "thumb flexion",
           "thumb rotation (towards opposition)")
#: A prosthetic joint's position and velocity units by its kind: its digits' hinges, and the
#: slide joints of a relaxation pad and its branches (representation ``soft-contact+relaxation``).
JOINT_UNITS = {"hinge": ("rad", "rad/s"), "slide": ("m", "m/s")}


def action_names() -> tuple[str, ...]:
    """``speed/{motor} [fraction of max]`` for the 6 motors, in action order."""
    return tuple(f"speed/{a} [{ACTION_UNIT}]" for a in prosthetic_actuators())


def observation_names(joints: Sequence[tuple[str, str]], regions: Sequence[str],
                      observe: str) -> tuple[str, ...]:
    """The name of every observation entry, in order.

    Args:
        joints: the prosthetic hand's joints in observation order, each (name, kind) with kind
            ``hinge`` or ``slide`` (`JOINT_UNITS`).
        regions: the sensing regions in observation order (the env's ``region_names``).
        observe: a key of `OBSERVE`.
    """
    units = [JOINT_UNITS[kind] for _, kind in joints]
    return (*(f"qpos/{j} [{u[0]}]" for (j, _), u in zip(joints, units, strict=True)),
            *(f"qvel/{j} [{u[1]}]" for (j, _), u in zip(joints, units, strict=True)),
            *(f"{block}/{r} [N]" for block in OBSERVE[observe] for r in regions),
            "episode_fraction [-]")


def region_values(observe: str, values: Mapping[str, np.ndarray]) -> np.ndarray:
    """The observation's region entries: the blocks of ``observe`` joined along the last axis,
    from ``values`` (block name -> the 18 values, or (W, 18) for W worlds)."""
    return np.concatenate([values[b] for b in OBSERVE[observe]], axis=-1)


def action_rows() -> list[tuple[str, str, str]]:
    """(index, name, what it drives) of each action, for the tables."""
    return [(str(i), name, what) for i, (name, what) in enumerate(zip(action_names(), _MOTORS,
                                                                      strict=True))]


def observation_rows() -> list[tuple[str, str, str]]:
    """(slice, name, quantity) of each part of the observation, with n the prosthetic hand's
    joints and ``<joint>``, ``<region>`` standing for each name: the region blocks a row per
    block and slot, naming the ``observe`` values that put it there."""
    rows = [("[0, n)", "qpos/<joint> [rad]", "prosthetic joint positions, in the model's order "
             "(pro_index_mcp, ...; a relaxation pad's slide joints in m)"),
            ("[n, 2n)", "qvel/<joint> [rad/s]", "prosthetic joint velocities (slides: m/s)")]
    default = next(iter(OBSERVE))
    for slot, where in enumerate(("[2n, 2n + 18)", "[2n + 18, 2n + 36)")):
        blocks = dict.fromkeys(b[slot] for b in OBSERVE.values() if len(b) > slot)
        for block in blocks:
            modes = [f'"{m}"' + (" (default)" if m == default else "")
                     for m, b in OBSERVE.items() if len(b) > slot and b[slot] == block]
            what, key = REGION_BLOCKS[block]
            rows.append((where, f"{block}/<region> [N]",
                         f"observe={' or '.join(modes)}: per region, {what} "
                         f'(info["{key}"])'))
    rows.append(("last", "episode_fraction [-]", "time since the start / handshake duration"))
    return rows


def _bullets(rows: list[tuple[str, ...]], width: int = 96) -> list[str]:
    """A Markdown bullet list, one row an item (``- first `name`: what``), wrapped to ``width``
    characters: it reads as text in ``help()`` and renders in the API reference, where a table
    of these long rows would not fit a docstring line."""
    out = []
    for first, name, what in rows:
        out += textwrap.wrap(f"- {first} `{name}`: {what}", width, subsequent_indent="  ",
                             break_long_words=False, break_on_hyphens=False)
    return out


def action_table(markdown: bool = False) -> str:
    """The actions: a bullet list for the docstring, or a Markdown table for the docs."""
    return _table(("index", "name", "drives"), action_rows(), markdown)


def observation_table(markdown: bool = False) -> str:
    """The observation's layout: a bullet list for the docstring, or a Markdown table."""
    return _table(("slice", "name", "quantity"), observation_rows(), markdown)


def _table(header: tuple[str, ...], rows: list[tuple[str, ...]], markdown: bool) -> str:
    if not markdown:
        return "\n".join(_bullets(rows))
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(f"`{c}`" if k == 1 else c for k, c in enumerate(r)) + " |"
              for r in rows]
    return "\n".join(lines)
