// Validates one glTF or GLB file with the Khronos glTF-Validator and prints its JSON
// report on standard output.
//
//     node tools/gltf-validator/validate.mjs FILE
//
// Exit status: 0 when the report has no errors and no warnings (infos and hints are
// printed but allowed), 1 when it has any, 2 when the file cannot be read or the
// validator cannot run. External resources (URIs) are loaded relative to FILE, so a
// .gltf with side files is checked whole; sdfc's .glb files have none.
//
// Installed by `npm ci` in this folder (see package.json; tests/common::gltf_validate
// runs this script).
import { readFile } from "node:fs/promises";
import { dirname, resolve } from "node:path";
import validator from "gltf-validator";

const file = process.argv[2];
if (!file || process.argv.length > 3) {
  console.error("usage: node validate.mjs FILE");
  process.exit(2);
}

try {
  const bytes = new Uint8Array(await readFile(file));
  const report = await validator.validateBytes(bytes, {
    uri: file,
    maxIssues: 0,
    writeTimestamp: false,
    externalResourceFunction: (uri) =>
      readFile(resolve(dirname(file), decodeURIComponent(uri))).then(
        (data) => new Uint8Array(data),
      ),
  });
  console.log(JSON.stringify(report, null, 2));
  const { numErrors, numWarnings } = report.issues;
  process.exit(numErrors > 0 || numWarnings > 0 ? 1 : 0);
} catch (error) {
  console.error(`glTF-Validator failed on ${file}: ${error}`);
  process.exit(2);
}
