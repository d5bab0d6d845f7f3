"""TOML for sweeps and fits: reading (``tomllib``, or ``tomli`` before Python 3.11) and
writing scenario dicts back to text."""

from __future__ import annotations

import json
import math
import sys
from typing import Any

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

__all__ = ["dumps", "tomllib"]


def _string(v: str) -> str:
    # JSON's escapes are TOML's, but for characters beyond the BMP, which JSON writes as
    # surrogate pairs: written as themselves instead (TOML is UTF-8).
    return json.dumps(v, ensure_ascii=False)


def _value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return _string(v)
    if isinstance(v, list):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_string(k)} = {_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(f"cannot write {v!r} to TOML")


def dumps(doc: dict[str, Any]) -> str:
    """A dict (as ``tomllib`` reads it) as TOML text; floats by ``repr``: the same bits."""
    lines: list[str] = []

    def table(prefix: str, node: dict[str, Any]) -> None:
        if prefix:
            lines.append(f"[{prefix}]")
        lines.extend(
            f"{_string(k)} = {_value(v)}" for k, v in node.items() if not isinstance(v, dict)
        )
        for k, v in node.items():
            if isinstance(v, dict):
                table(f"{prefix}.{_string(k)}" if prefix else _string(k), v)

    table("", doc)
    return "\n".join(lines) + "\n"
