// Loads an unpacked VSIX's extension.js the way VS Code's extension host does,
// with `vscode` stubbed, and prints the files it loaded as JSON.
// Usage: node load-extension.js UNPACKED_VSIX_DIR
"use strict";
const Module = require("module");
const path = require("path");

const root = path.resolve(process.argv[2]);

// A stand-in for the `vscode` API: every property is another stand-in, callable
// and constructible, so modules that extend or call vscode classes at load time work.
function stub() {
  const target = function () {};
  return new Proxy(target, {
    get(t, key) {
      if (key === "prototype") return t.prototype;
      if (key === Symbol.toPrimitive) return () => "vscode-stub";
      if (!(key in t) || typeof key === "symbol") t[key] = stub();
      return t[key];
    },
    apply: () => stub(),
    construct: () => stub(),
  });
}
const vscode = stub();
const resolve = Module._resolveFilename;
Module._resolveFilename = function (request, ...rest) {
  return request === "vscode" ? "vscode" : resolve.call(this, request, ...rest);
};
require.cache.vscode = { id: "vscode", filename: "vscode", loaded: true, exports: vscode };

const manifest = require(path.join(root, "extension", "package.json"));
const extension = require(path.join(root, "extension", manifest.main));
console.log(
  JSON.stringify({
    exports: Object.keys(extension),
    loaded: Object.keys(require.cache).filter((f) => f !== "vscode" && f !== __filename),
  })
);
