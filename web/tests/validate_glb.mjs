// Khronos' glTF validator on GLB files: node web/tests/validate_glb.mjs FILE.glb...
// Prints one line per file (errors, warnings, infos, hints, and every message that is an error or
// a warning) and exits 1 when any file has an error or a warning, 2 when a file cannot be read.
import { readFile } from 'node:fs/promises';
import { basename } from 'node:path';
import validator from 'gltf-validator';

const files = process.argv.slice(2);
if (files.length === 0) {
  console.error('usage: node validate_glb.mjs FILE.glb...');
  process.exit(2);
}
let failed = false;
for (const file of files) {
  let bytes;
  try {
    bytes = new Uint8Array(await readFile(file));
  } catch (e) {
    console.error(`${file}: ${e.message}`);
    process.exit(2);
  }
  const report = await validator.validateBytes(bytes, { uri: basename(file), maxIssues: 0 });
  const issues = report.issues;
  console.log(`${file}: ${issues.numErrors} errors, ${issues.numWarnings} warnings, ` +
              `${issues.numInfos} infos, ${issues.numHints} hints` +
              (report.info && report.info.extensionsUsed
                   ? ` (extensions: ${report.info.extensionsUsed.join(', ')})` : ''));
  for (const m of issues.messages) {
    const severity = ['error', 'warning', 'info', 'hint'][m.severity];
    console.log(`  ${severity} ${m.code} at ${m.pointer ?? '-'}: ${m.message}`);
  }
  if (issues.numErrors > 0 || issues.numWarnings > 0) failed = true;
}
process.exit(failed ? 1 : 0);
