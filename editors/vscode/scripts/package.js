#!/usr/bin/env node
// Builds the VSIX: `npm run package [-- --out FILE]` (from editors/vscode).
//
// The manifest in this folder points at ../../grammar/ so that the grammar has
// one copy and `code --extensionDevelopmentPath` uses it as it is. A VSIX holds
// only what is inside the extension folder, so `vsce package` cannot run here
// directly. This script stages the extension in build/vsix/:
//
//   package.json          the manifest, with every contributed path that leads
//                         outside this folder rewritten to the copy below,
//                         and without scripts and devDependencies;
//   extension.js, README.md;
//   syntaxes/sdf.tmLanguage.json, language-configuration.json
//                         copies of ../../grammar/;
//   node_modules/         the production dependencies (vscode-languageclient
//                         and what it needs), as `npm ls --omit=dev` lists them;
//   .vscodeignore         leaves out their *.ts and *.map files;
//
// then runs `vsce package` there. The VSIX goes to sdfc-VERSION.vsix beside
// this script's folder unless --out says otherwise.
"use strict";

const fs = require("fs");
const path = require("path");
const cp = require("child_process");

const ROOT = path.resolve(__dirname, "..");
const STAGE = path.join(ROOT, "build", "vsix");
const ON_WINDOWS = process.platform === "win32";

/** Where each contributed file that lives outside the extension goes in the VSIX. */
function stagedPath(kind, source) {
  const base = path.basename(source);
  return kind === "grammar" ? `./syntaxes/${base}` : `./${base}`;
}

function isInside(dir, file) {
  const rel = path.relative(dir, file);
  return rel !== "" && !rel.startsWith("..") && !path.isAbsolute(rel);
}

/** Copies one contributed file into the stage, rewriting its manifest path when it lies outside. */
function stageContributed(kind, manifestPath) {
  const source = path.resolve(ROOT, manifestPath);
  if (!fs.existsSync(source)) {
    throw new Error(`package.json contributes ${kind} ${manifestPath}, which does not exist (${source})`);
  }
  const target = isInside(ROOT, source) ? manifestPath : stagedPath(kind, source);
  const dest = path.join(STAGE, target);
  fs.mkdirSync(path.dirname(dest), { recursive: true });
  fs.copyFileSync(source, dest);
  return target;
}

function stageManifest() {
  const manifest = JSON.parse(fs.readFileSync(path.join(ROOT, "package.json"), "utf8"));
  const contributes = manifest.contributes || {};
  for (const language of contributes.languages || []) {
    if (language.configuration) {
      language.configuration = stageContributed("configuration", language.configuration);
    }
  }
  for (const grammar of contributes.grammars || []) {
    grammar.path = stageContributed("grammar", grammar.path);
  }
  // The stage is built, not developed: no prepublish guard, no test tools.
  delete manifest.scripts;
  delete manifest.devDependencies;
  fs.writeFileSync(path.join(STAGE, "package.json"), JSON.stringify(manifest, null, 2) + "\n");
  return manifest;
}

function run(command, args, options = {}) {
  const result = cp.spawnSync(command, args, {
    cwd: ROOT,
    encoding: "utf8",
    shell: ON_WINDOWS,
    ...options,
  });
  if (result.error) throw result.error;
  if (result.status !== 0) {
    throw new Error(`${command} ${args.join(" ")} exited ${result.status}\n${result.stdout || ""}${result.stderr || ""}`);
  }
  return result.stdout;
}

/** Copies the production dependency tree (not vsce and the test tools) into the stage. */
function stageDependencies() {
  const listed = run("npm", ["ls", "--omit=dev", "--all", "--parseable"])
    .split(/\r?\n/)
    .map((line) => line.trim())
    .filter((line) => line && path.resolve(line) !== ROOT);
  for (const dir of listed) {
    if (!isInside(path.join(ROOT, "node_modules"), dir)) {
      throw new Error(`dependency outside node_modules: ${dir}`);
    }
    // Each nested node_modules folder is listed on its own line, and only the
    // production ones are; skip them here so no dev-only package slips in.
    fs.cpSync(dir, path.join(STAGE, path.relative(ROOT, dir)), {
      recursive: true,
      filter: (src) => src === dir || path.basename(src) !== "node_modules",
    });
  }
  return listed.length;
}

function parseArgs(argv) {
  const options = { out: null };
  for (let i = 0; i < argv.length; i++) {
    if (argv[i] === "--out" || argv[i] === "-o") options.out = path.resolve(argv[++i]);
    else throw new Error(`unknown argument ${argv[i]} (usage: package.js [--out FILE.vsix])`);
  }
  return options;
}

function main() {
  const options = parseArgs(process.argv.slice(2));
  if (!fs.existsSync(path.join(ROOT, "node_modules", "vscode-languageclient"))) {
    throw new Error("node_modules is missing: run `npm ci` (or `npm install`) in editors/vscode first");
  }
  fs.rmSync(STAGE, { recursive: true, force: true });
  fs.mkdirSync(STAGE, { recursive: true });
  const manifest = stageManifest();
  for (const file of [manifest.main || "extension.js", "README.md"]) {
    fs.copyFileSync(path.join(ROOT, file), path.join(STAGE, file));
  }
  const dependencies = stageDependencies();
  // Types and source maps of the dependencies are not needed at run time.
  fs.writeFileSync(path.join(STAGE, ".vscodeignore"), "**/*.ts\n**/*.map\n");
  const out = options.out || path.join(ROOT, `${manifest.name}-${manifest.version}.vsix`);
  fs.mkdirSync(path.dirname(out), { recursive: true });
  const vsce = require.resolve("@vscode/vsce/vsce");
  // No repository URL or license file exists to point at yet; without these
  // two flags vsce would stop and ask.
  run(process.execPath, [vsce, "package", "--out", out, "--allow-missing-repository", "--skip-license"], {
    cwd: STAGE,
    shell: false,
    stdio: ["ignore", "inherit", "inherit"],
  });
  console.log(`staged ${path.relative(ROOT, STAGE)} with ${dependencies} production packages; wrote ${out}`);
  return out;
}

if (require.main === module) {
  try {
    main();
  } catch (error) {
    console.error(`package.js: ${error.message}`);
    process.exit(1);
  }
}
