#!/usr/bin/env python3
"""Checks a goalseek MCAP recording against the official Foxglove JSON schemas (npm
@foxglove/schemas, printed by foxglove_schemas.cjs into SCHEMAS.json): every JSON message is
validated with the `jsonschema` package, and every property of the official schema must appear
in the schema embedded in the file with the same type and title. Prints one JSON object.

Usage: foxglove_schema_check.py FILE.mcap SCHEMAS.json
"""

import json
import sys

import jsonschema
from mcap.reader import make_reader


def mismatches(official, embedded, where):
    """Properties of `official` that `embedded` lacks or types differently, recursively."""
    out = []
    for key in ("type", "title"):
        if key in official and official.get(key) != embedded.get(key):
            out.append(f"{where}: {key} {embedded.get(key)!r} != {official[key]!r}")
    items = official.get("items")
    if isinstance(items, dict):
        out += mismatches(items, embedded.get("items") or {}, where + "[]")
    for name, prop in (official.get("properties") or {}).items():
        mine = (embedded.get("properties") or {}).get(name)
        if mine is None:
            out.append(f"{where}.{name}: missing")
        else:
            out += mismatches(prop, mine, f"{where}.{name}")
    return out


def main():
    path, schemas_path = sys.argv[1], sys.argv[2]
    with open(schemas_path) as f:
        official = json.load(f)
    report = {"channels": {}, "schema_mismatches": {}}
    with open(path, "rb") as f:
        reader = make_reader(f)
        for schema, channel, message in reader.iter_messages():
            if channel.message_encoding != "json" or schema is None:
                continue
            c = report["channels"].setdefault(
                channel.topic, {"schema": schema.name, "messages": 0, "valid": 0, "first_error": None}
            )
            if schema.name not in report["schema_mismatches"]:
                embedded = json.loads(schema.data)
                ref = official.get(schema.name)
                report["schema_mismatches"][schema.name] = (
                    None if ref is None else mismatches(ref, embedded, schema.name)
                )
            c["messages"] += 1
            ref = official.get(schema.name)
            if ref is None:
                continue
            try:
                jsonschema.validate(json.loads(message.data), ref)
                c["valid"] += 1
            except jsonschema.ValidationError as e:
                if c["first_error"] is None:
                    c["first_error"] = f"{list(e.absolute_path)}: {e.message}"[:300]
    json.dump(report, sys.stdout)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
