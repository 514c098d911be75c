// Runs the Khronos glTF validator (npm gltf-validator) on each file given; prints every
// message and exits non-zero if any file has an error or a warning.
//
//   NODE_PATH=<dir with node_modules> node gltf_validate.js FILE.glb [FILE.gltf ...]
const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

async function check(file) {
  const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
    uri: path.basename(file),
    externalResourceFunction: (uri) =>
      new Promise((resolve) => resolve(new Uint8Array(fs.readFileSync(path.join(path.dirname(file), uri))))),
  });
  const i = report.issues;
  for (const m of i.messages) console.log(`${file}: ${['error', 'warning', 'info', 'hint'][m.severity]} ${m.code} ${m.pointer || ''}: ${m.message}`);
  console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos, ${i.numHints} hints (validator ${report.validatorVersion})`);
  return i.numErrors + i.numWarnings;
}

(async () => {
  let bad = 0;
  for (const f of process.argv.slice(2)) bad += await check(f);
  process.exit(bad > 0 ? 1 : 0);
})().catch((e) => { console.error(e); process.exit(2); });
