"""Dotted-key overrides of a scene (``--set mesh.density=24x8x4``, ``Scene.with_overrides``).

:func:`parse_overrides` reads ``key=value`` items (each value a TOML value if it parses as one);
:func:`apply` sets them in a copy of the scene's TOML table, which the schema then validates as if
the file had said so (unknown keys are errors, as in a file).
"""

from __future__ import annotations

import copy
import tomllib

from ..errors import InputError

__all__ = ["apply", "parse_value", "parse_overrides"]


def _index(node: list, part: str, key: str, what: str) -> int:
    try:
        i = int(part)
        node[i]
        return i
    except (ValueError, IndexError):
        raise InputError(f"override {key!r}: {what} is not an index of the array") from None


def _set(raw: dict, key: str, value) -> None:
    if not isinstance(key, str) or not key or any(not p for p in key.split(".")):
        raise InputError(f"override {key!r}: expected a dotted key like 'mesh.density'")
    parts = key.split(".")
    node = raw
    for i, p in enumerate(parts[:-1]):
        here = ".".join(parts[: i + 1])
        if isinstance(node, list):
            node = node[_index(node, p, key, here)]
            continue
        if not isinstance(node, dict):
            raise InputError(f"override {key!r}: {here} is not a table")
        node = node.setdefault(p, {})
    last = parts[-1]
    if isinstance(node, list):
        node[_index(node, last, key, repr(last))] = value
    elif isinstance(node, dict):
        if parts == ["geometry", "file"]:  # a mesh file replaces the recipe and its lengths
            node.clear()
        node[last] = value
    else:
        raise InputError(f"override {key!r}: the parent is not a table")


def apply(raw: dict, overrides: dict) -> dict:
    """A copy of the scene table ``raw`` with the dotted keys of ``overrides`` set
    (``{"mesh.density": "24x8x4", "solver.static.c": 2e-3, "contact.0.radius": 6.0}``)."""
    raw = copy.deepcopy(raw)
    for key, value in overrides.items():
        _set(raw, key, value)
    if "geometry.file" in overrides:  # a mesh file has no recipe densities
        for k in ("density", "paper_meshes", "adaptive_level0"):
            if f"mesh.{k}" not in overrides:
                raw.get("mesh", {}).pop(k, None)
    # a fabric is named (material.fabric) or given by its KES data (material.kes): setting one
    # replaces the other the file gave; setting both is the schema's error
    kes = any(k == "material.kes" or k.startswith("material.kes.") for k in overrides)
    if kes != ("material.fabric" in overrides) and isinstance(raw.get("material"), dict):
        raw["material"].pop("fabric" if kes else "kes", None)
    return raw


def parse_value(text: str):
    """A --set value: a TOML value if it parses as one (2e-3, true, [1, 2], "x"), else the string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def parse_overrides(items) -> dict:
    """['key=value', ...] -> {key: parsed value}."""
    out = {}
    for it in items or []:
        if "=" not in it:
            raise InputError(f"--set {it!r}: expected key=value, e.g. solver.static.c=2e-3")
        k, v = it.split("=", 1)
        k = k.strip()
        if not k:
            raise InputError(f"--set {it!r}: empty key")
        out[k] = parse_value(v.strip())
    return out
