// Validates .glb files with the Khronos glTF validator (npm package gltf-validator).
// Usage: node validate_gltf.cjs FILE.glb...   (NODE_PATH must reach gltf-validator)
// Prints one line per file; exits 1 if any file has an error (warnings are printed, not fatal).
const fs = require('fs');
const validator = require('gltf-validator');

async function main() {
  let failed = false;
  for (const file of process.argv.slice(2)) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
      maxIssues: 50,
    });
    const i = report.issues;
    const info = report.info || {};
    console.log(`${i.numErrors === 0 ? 'ok' : 'FAIL'} ${file}: ${i.numErrors} errors, ` +
      `${i.numWarnings} warnings, ${i.numInfos} infos; ${info.totalVertexCount} vertices, ` +
      `${info.animationCount || 0} animations, morph targets: ${info.hasMorphTargets}`);
    for (const m of i.messages) {
      if (m.severity <= 1) console.log(`  [${m.severity === 0 ? 'error' : 'warning'}] ${m.code} ${m.pointer || ''}: ${m.message}`);
    }
    if (i.numErrors > 0) failed = true;
  }
  console.log('check_gltf:', failed ? 'FAILED' : 'passed');
  process.exit(failed ? 1 : 0);
}
main().catch((e) => { console.error(e); process.exit(1); });
