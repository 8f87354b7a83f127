"""Stored references a run is compared with by what it is (not by its name): the heavy elastica of
reference/elastica_strip.json for a clamped strip under its own weight.  The CLI's final line
and the strip's side picture both ask here."""

from __future__ import annotations

import json
from importlib import resources


def strip_elastica(s: dict) -> tuple[str, dict] | None:
    """The stored heavy elastica (reference/elastica_strip.json) this strip is, if it is one of them:
    the strip recipe of the same length under gravity alone, clamped at one end, with the same weight
    per area and bending rigidity along the strip (warp along it or across it)."""
    g, m = s.get("geometry") or {}, s.get("material") or {}
    loads = (s.get("scene_inputs") or {}).get("loads") or {}
    if (
        s.get("recipe") != "strip"
        or not loads.get("gravity")
        or any(loads.get(k) for k in ("point", "line", "surface"))
    ):
        return None
    if list(loads.get("gravity_direction") or [0, 0, -1]) != [0.0, 0.0, -1.0] or s.get("perturbation"):
        return None
    if s.get("supports") != {"clamped": ["clamped"]}:
        return None
    angle = float(m.get("warp_angle_deg", 0.0)) % 180.0
    Cb = m.get("C_b")
    if Cb is None or not (abs(angle) < 1e-9 or abs(angle - 90.0) < 1e-9):
        return None
    B = float(Cb[0][0] if angle < 45.0 else Cb[1][1])
    try:
        table = json.loads((resources.files("reference") / "elastica_strip.json").read_text())["strip"]
    except (ImportError, OSError, KeyError, ValueError):
        return None
    for cut, ref in table.items():
        same = [
            (float(g.get("length", -1.0)), ref["L"]),
            (B, ref["B"]),
            (float(m.get("weight_per_area", -1.0)), ref["w"] / ref["width"]),
        ]
        if all(abs(a - b) <= 1e-9 * abs(b) for a, b in same):
            return cut, ref
    return None
