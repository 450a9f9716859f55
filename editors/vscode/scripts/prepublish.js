#!/usr/bin/env node
// `vsce package` run directly in editors/vscode would pack a manifest whose
// grammar and language configuration point at ../../grammar/, outside the
// VSIX. `npm run package` stages a copy with those files inside and packs
// that (its staged manifest has no scripts, so this guard does not run there).
console.error(
  "Run `npm run package` in editors/vscode: it copies grammar/ into a staged " +
    "extension (build/vsix/) and runs vsce there. Plain `vsce package` here would " +
    "build a VSIX without the grammar and language configuration."
);
process.exit(1);
