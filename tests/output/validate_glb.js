// Usage: node validate_glb.js <node_modules dir> file.glb ... ; exit 0 when no file has errors.
const path = require('path');
const fs = require('fs');
const validator = require(path.join(process.argv[2], 'gltf-validator'));
(async () => {
  let bad = 0;
  for (const f of process.argv.slice(3)) {
    const r = await validator.validateBytes(new Uint8Array(fs.readFileSync(f)));
    console.log(f + ': errors ' + r.issues.numErrors + ', warnings ' + r.issues.numWarnings);
    for (const m of r.issues.messages) if (m.severity === 0) console.log('  ' + m.code + ' ' + m.message + ' ' + (m.pointer || ''));
    if (r.issues.numErrors > 0) bad++;
  }
  process.exit(bad ? 1 : 0);
})().catch(e => { console.log(e); process.exit(2); });
