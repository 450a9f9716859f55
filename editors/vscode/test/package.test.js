// `npm run package` builds a VSIX that holds the grammar, the language
// configuration, the manifest, extension.js and its dependencies, with every
// path the manifest contributes resolving inside the VSIX; plain `vsce package`
// in the source folder refuses instead of building a VSIX without the grammar.
"use strict";

const { test, before, after } = require("node:test");
const assert = require("node:assert/strict");
const cp = require("node:child_process");
const fs = require("node:fs");
const os = require("node:os");
const path = require("node:path");
const yauzl = require("yauzl");

const EXTENSION = path.resolve(__dirname, "..");
const REPO = path.resolve(EXTENSION, "..", "..");
const GRAMMAR = path.join(REPO, "grammar", "sdf.tmLanguage.json");
const CONFIGURATION = path.join(REPO, "grammar", "language-configuration.json");

let tmp;
let vsix; // the VSIX's path
let entries; // Map: name in the zip → contents

async function readZip(file) {
  const zip = await yauzl.openPromise(file, { lazyEntries: true, autoClose: false });
  const out = new Map();
  try {
    for await (const entry of zip.eachEntry()) {
      if (entry.fileName.endsWith("/")) continue;
      const stream = await zip.openReadStreamPromise(entry);
      const chunks = [];
      for await (const chunk of stream) chunks.push(chunk);
      out.set(entry.fileName, Buffer.concat(chunks));
    }
  } finally {
    zip.close();
  }
  return out;
}

/** The entry a path in the packaged manifest names, or null when it leaves extension/. */
function entryFor(manifestPath) {
  const name = path.posix.normalize(path.posix.join("extension", manifestPath));
  return name.startsWith("extension/") ? name : null;
}

function packagedManifest() {
  return JSON.parse(entries.get("extension/package.json").toString("utf8"));
}

before(() => {
  tmp = fs.mkdtempSync(path.join(os.tmpdir(), "sdfc-vsix-"));
  vsix = path.join(tmp, "sdfc.vsix");
  const result = cp.spawnSync(process.execPath, [path.join(EXTENSION, "scripts", "package.js"), "--out", vsix], {
    cwd: EXTENSION,
    encoding: "utf8",
  });
  assert.equal(result.status, 0, `scripts/package.js (npm run package) failed:\n${result.stdout}\n${result.stderr}`);
  return readZip(vsix).then((map) => {
    entries = map;
  });
});

after(() => {
  if (tmp) fs.rmSync(tmp, { recursive: true, force: true });
});

test("the VSIX holds package.json, extension.js, the grammar and the language configuration", () => {
  for (const name of [
    "extension.vsixmanifest",
    "extension/package.json",
    "extension/extension.js",
    "extension/syntaxes/sdf.tmLanguage.json",
    "extension/language-configuration.json",
    "extension/node_modules/vscode-languageclient/node.js",
  ]) {
    assert.ok(entries.has(name), `${name} missing from the VSIX; it has:\n${[...entries.keys()].join("\n")}`);
  }
  // Only the production dependencies: no packaging or test tools.
  for (const name of entries.keys()) {
    assert.doesNotMatch(name, /node_modules\/(@vscode\/vsce|vscode-textmate|vscode-oniguruma|yauzl)\//, name);
  }
});

test("the packaged manifest's contributed paths resolve to the grammar files inside the VSIX", () => {
  const manifest = packagedManifest();
  const { languages, grammars } = manifest.contributes;
  assert.ok(languages.length > 0 && grammars.length > 0);
  const grammarText = fs.readFileSync(GRAMMAR);
  const configText = fs.readFileSync(CONFIGURATION);
  for (const language of languages) {
    const name = entryFor(language.configuration);
    assert.ok(name && entries.has(name), `languages[${language.id}].configuration ${language.configuration} is not in the VSIX`);
    assert.ok(entries.get(name).equals(configText), `${name} differs from grammar/language-configuration.json`);
  }
  for (const grammar of grammars) {
    const name = entryFor(grammar.path);
    assert.ok(name && entries.has(name), `grammars[${grammar.language}].path ${grammar.path} is not in the VSIX`);
    assert.ok(entries.get(name).equals(grammarText), `${name} differs from grammar/sdf.tmLanguage.json`);
    assert.equal(JSON.parse(entries.get(name)).scopeName, grammar.scopeName);
    assert.ok(languages.some((l) => l.id === grammar.language), `grammar for unknown language ${grammar.language}`);
  }
  const main = entryFor(manifest.main);
  assert.ok(main && entries.has(main), `main ${manifest.main} is not in the VSIX`);
});

test("the packaged manifest is the source manifest with only the copied paths changed", () => {
  const source = JSON.parse(fs.readFileSync(path.join(EXTENSION, "package.json"), "utf8"));
  const packaged = packagedManifest();
  for (const key of ["name", "publisher", "version", "main", "engines", "activationEvents", "dependencies"]) {
    assert.deepEqual(packaged[key], source[key], key);
  }
  assert.deepEqual(packaged.contributes.configuration, source.contributes.configuration);
  assert.equal(packaged.scripts, undefined, "no prepublish guard in the packaged manifest");
  assert.equal(packaged.devDependencies, undefined);
  // The source manifest keeps pointing at the one copy in grammar/.
  assert.equal(path.resolve(EXTENSION, source.contributes.grammars[0].path), GRAMMAR);
  assert.equal(path.resolve(EXTENSION, source.contributes.languages[0].configuration), CONFIGURATION);
});

test("extension.js loads from the unpacked VSIX with only the VSIX's own modules", () => {
  const unpacked = path.join(tmp, "unpacked");
  for (const [name, contents] of entries) {
    const file = path.join(unpacked, ...name.split("/"));
    fs.mkdirSync(path.dirname(file), { recursive: true });
    fs.writeFileSync(file, contents);
  }
  const result = cp.spawnSync(process.execPath, [path.join(__dirname, "load-extension.js"), unpacked], {
    cwd: unpacked,
    encoding: "utf8",
    env: { ...process.env, NODE_PATH: "" },
  });
  assert.equal(result.status, 0, result.stderr);
  const { exports, loaded } = JSON.parse(result.stdout);
  assert.deepEqual(exports.sort(), ["activate", "deactivate"]);
  assert.ok(loaded.some((f) => f.endsWith(path.join("vscode-languageclient", "node.js"))), loaded.join("\n"));
  for (const file of loaded) {
    assert.ok(file.startsWith(unpacked + path.sep), `${file} was loaded from outside the VSIX`);
  }
});

test("plain `vsce package` in editors/vscode refuses and points at `npm run package`", () => {
  const out = path.join(tmp, "direct.vsix");
  const vsce = require.resolve("@vscode/vsce/vsce");
  const result = cp.spawnSync(process.execPath, [vsce, "package", "--out", out, "--allow-missing-repository", "--skip-license"], {
    cwd: EXTENSION,
    encoding: "utf8",
    stdio: ["ignore", "pipe", "pipe"],
  });
  assert.notEqual(result.status, 0, "vsce package succeeded in the source folder");
  assert.match(result.stdout + result.stderr, /npm run package/);
  assert.ok(!fs.existsSync(out));
});
