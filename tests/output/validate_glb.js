// Usage: node validate_glb.js <node_modules dir> file.glb ...
// Runs the Khronos glTF Validator (npm gltf-validator, pinned in tests/browser/package-lock.json;
// scripts/test installs it into <build>/tools/node_modules) on each file and prints, per file, the
// counts of errors, warnings, infos and hints, every error and warning, and the codes of the infos.
// Exit 0 when no file has an error or a warning that is not listed in ALLOWED_WARNINGS; 1 otherwise;
// 2 when the validator cannot be loaded or fails.
// Infos are printed, never fatal: today's Draco GLBs get UNSUPPORTED_EXTENSION (the validator does not
// decode KHR_draco_mesh_compression, so the compressed geometry is not checked by it; tests/draco and
// three's DRACOLoader in tests/browser read it) and UNUSED_OBJECT (the Draco payload's bufferView is
// referenced only from the extension).
'use strict';
const path = require('path');
const fs = require('fs');

// Warning codes that are accepted, each with why. Empty: every warning fails.
const ALLOWED_WARNINGS = {
};

(async () => {
  const validator = require(path.join(path.resolve(process.argv[2]), 'gltf-validator'));
  console.log('gltf-validator ' + validator.version());
  let bad = 0;
  for (const f of process.argv.slice(3)) {
    const r = await validator.validateBytes(new Uint8Array(fs.readFileSync(f)), { maxIssues: 0 });
    const is = r.issues;
    const allowed = is.messages.filter((m) => m.severity === 1 && m.code in ALLOWED_WARNINGS).length;
    console.log(`${f}: errors ${is.numErrors}, warnings ${is.numWarnings}` + (allowed ? ` (${allowed} allowed)` : '') +
                `, infos ${is.numInfos}, hints ${is.numHints}`);
    for (const m of is.messages) {
      if (m.severity === 0) console.log(`  error ${m.code} ${m.message} ${m.pointer || ''}`);
      if (m.severity === 1) console.log(`  warning ${m.code} ${m.message} ${m.pointer || ''}` +
                                        (m.code in ALLOWED_WARNINGS ? ` [allowed: ${ALLOWED_WARNINGS[m.code]}]` : ''));
    }
    const infos = [...new Set(is.messages.filter((m) => m.severity === 2).map((m) => m.code))];
    if (infos.length) console.log('  infos: ' + infos.join(', '));
    if (is.truncated) console.log('  (the validator truncated its list of issues)');
    if (is.numErrors > 0 || is.numWarnings > allowed) bad++;
  }
  process.exit(bad ? 1 : 0);
})().catch((e) => { console.log('validate_glb.js: ' + (e && e.stack || e)); process.exit(2); });
