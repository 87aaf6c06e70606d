"""The JSON form of a mission's metrics row (``run --json``, ``compare --json``): exact numbers
as JSON numbers with exact string twins, embedded JSON and histograms as arrays and objects."""

import json
from collections.abc import Mapping
from fractions import Fraction

from selfrepair.cli._app import exact_json, number_json
from selfrepair.textio import JSONObject, JSONValue

__all__ = ["row_json"]

_EXACT = ("ticks", "plan_cost_before", "plan_cost_after", "clearance_weight")
"""Columns that hold an exact number as text (``"31/3"``)."""
_EMBEDDED_JSON = ("fault_schedule", "repair_latencies_ns")
"""Columns that hold JSON text (for the results database)."""
_HISTOGRAMS = ("replacement_lengths", "replacement_depths")
"""Columns that hold a ``value:count,...`` histogram as text."""


def row_json(row: Mapping[str, int | float | str | None]) -> JSONObject:
    """A mission's metrics row (``mission_row``) as JSON values: numbers are JSON numbers
    (``ticks`` and the other exact values with an exact ``_exact`` string twin, the ``_float``
    twins dropped; floats rounded), ``reached`` a boolean, and the embedded JSON and histogram
    texts as arrays and objects."""
    out: JSONObject = {}
    for key, value in row.items():
        if key.endswith("_float") and key.removesuffix("_float") in _EXACT:
            continue
        if key in _EXACT:
            exact = None if value is None else Fraction(str(value))
            out[key] = number_json(exact)
            out[f"{key}_exact"] = exact_json(exact)
        elif key in _EMBEDDED_JSON:
            embedded: JSONValue = json.loads(str(value))
            out[key] = embedded
        elif key in _HISTOGRAMS:
            pairs = (item.split(":") for item in str(value or "").split(",") if item)
            out[key] = {length: int(count) for length, count in pairs}
        elif key == "reached":
            out[key] = bool(value)
        elif key.endswith("_ns") and isinstance(value, float):
            out[key] = round(value)
        elif isinstance(value, float):
            out[key] = number_json(value)
        else:
            out[key] = value
    return out
