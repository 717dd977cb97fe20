// Validate .glb files with the Khronos glTF validator (npm gltf-validator).
// Usage: node tools/validate_gltf.js FILE.glb ...
// Prints each file's error, warning and info counts and every error and
// warning; exits 1 if any file has an error. tools/check_bakes.py installs
// the validator under target/gltf-validator and calls this.
"use strict";
const fs = require("fs");
const path = require("path");

const validatorDir = process.env.GLTF_VALIDATOR_DIR || path.join(__dirname, "..", "target", "gltf-validator", "node_modules", "gltf-validator");
const validator = require(validatorDir);

async function main(files) {
  let failed = false;
  for (const file of files) {
    const bytes = new Uint8Array(fs.readFileSync(file));
    const report = await validator.validateBytes(bytes, {
      uri: path.basename(file),
      maxIssues: 200,
      // A .glb from organtex is self-contained: any external reference is an
      // error.
      externalResourceFunction: (uri) => Promise.reject(new Error(`external resource ${uri}`)),
    });
    const i = report.issues;
    console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos`);
    for (const m of i.messages) {
      if (m.severity <= 1) {
        console.log(`  ${m.severity === 0 ? "error" : "warning"} ${m.code} at ${m.pointer || "-"}: ${m.message}`);
      }
    }
    if (i.numErrors > 0) failed = true;
  }
  process.exit(failed ? 1 : 0);
}

main(process.argv.slice(2)).catch((e) => {
  console.error(e);
  process.exit(2);
});
