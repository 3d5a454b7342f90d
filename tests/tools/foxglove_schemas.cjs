// Prints, as one JSON object, the official Foxglove JSON schemas (npm @foxglove/schemas) of the
// schema names given on the command line, e.g. `node foxglove_schemas.cjs foxglove.LaserScan`.
"use strict";
const schemas = require("@foxglove/schemas/jsonschema");
const out = {};
for (const name of process.argv.slice(2)) {
  const key = name.replace(/^foxglove\./, "");
  if (!(key in schemas)) {
    console.error(`no official schema named ${name}`);
    process.exit(2);
  }
  out[name] = schemas[key];
}
process.stdout.write(JSON.stringify(out) + "\n");
