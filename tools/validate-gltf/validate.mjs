#!/usr/bin/env node
// Validates glTF/GLB files with the Khronos glTF-Validator and prints one JSON summary per
// file: {"file", "errors", "warnings", "infos", "hints", "messages": [...]}.
// Exit status: 0 when no file has errors, 1 when some file has errors, 2 on usage or I/O
// problems. External resources (buffers, images) are resolved next to each file.
import { readFile } from "node:fs/promises";
import path from "node:path";
import validator from "gltf-validator";

const files = process.argv.slice(2);
if (files.length === 0) {
  console.error("usage: validate.mjs FILE.glb|FILE.gltf ...");
  process.exit(2);
}

let failed = false;
for (const file of files) {
  let data;
  try {
    data = new Uint8Array(await readFile(file));
  } catch (e) {
    console.error(`${file}: cannot read: ${e.message}`);
    process.exit(2);
  }
  const report = await validator.validateBytes(data, {
    uri: path.basename(file),
    maxIssues: 200,
    externalResourceFunction: (uri) =>
      readFile(path.resolve(path.dirname(file), decodeURIComponent(uri))).then((b) => new Uint8Array(b)),
  });
  const issues = report.issues;
  const summary = {
    file,
    errors: issues.numErrors,
    warnings: issues.numWarnings,
    infos: issues.numInfos,
    hints: issues.numHints,
    messages: issues.messages.map((m) => ({ code: m.code, severity: m.severity, pointer: m.pointer, message: m.message })),
  };
  console.log(JSON.stringify(summary));
  if (issues.numErrors > 0) failed = true;
}
process.exit(failed ? 1 : 0);
