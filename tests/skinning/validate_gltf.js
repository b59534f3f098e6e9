// SPDX-License-Identifier: MIT
// Runs the Khronos glTF validator (npm package gltf-validator) on the files given: one line per
// file with its counts, one line per message; exit 1 when a file has an error or a warning, 77
// (CTest's "skipped") when the validator is not installed (npm install -g gltf-validator).
'use strict';
const fs = require('fs');
const path = require('path');

function load_validator() {
  try {
    return require('gltf-validator');
  } catch (e) {
    try {
      const root = require('child_process').execSync('npm root -g', {stdio: ['ignore', 'pipe', 'ignore']});
      return require(path.join(root.toString().trim(), 'gltf-validator'));
    } catch (e2) {
      return null;
    }
  }
}

async function main() {
  const validator = load_validator();
  if (!validator) {
    console.log('gltf-validator is not installed (npm install -g gltf-validator)');
    return 77;
  }
  console.log('gltf-validator ' + validator.version());
  let failed = 0;
  for (const file of process.argv.slice(2)) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
      uri: path.basename(file),
      maxIssues: 50,
      externalResourceFunction: (uri) => Promise.reject(new Error('no external resources: ' + uri)),
    });
    const i = report.issues;
    console.log(`${file}: errors ${i.numErrors} warnings ${i.numWarnings} infos ${i.numInfos} hints ${i.numHints}`);
    for (const m of i.messages) console.log(`  severity ${m.severity} ${m.code} ${m.pointer || ''}: ${m.message}`);
    if (i.numErrors > 0 || i.numWarnings > 0) failed = 1;
  }
  return failed;
}

main().then((code) => process.exit(code), (e) => {
  console.log('validator failed: ' + e);
  process.exit(2);
});
