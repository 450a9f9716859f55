// Starts `sdfc lsp` for *.sdf files: diagnostics, hover, definition,
// references, outline, formatting, semantic tokens, rename, completion and
// signature help all come from the server.
const vscode = require("vscode");
const { LanguageClient } = require("vscode-languageclient/node");

let client;

function activate(context) {
  const command = vscode.workspace.getConfiguration("sdfc").get("path") || "sdfc";
  const server = { command, args: ["lsp"] };
  client = new LanguageClient(
    "sdfc",
    "sdfc language server",
    { run: server, debug: server },
    { documentSelector: [{ scheme: "file", language: "sdf" }, { scheme: "untitled", language: "sdf" }] }
  );
  context.subscriptions.push(client);
  return client.start();
}

function deactivate() {
  return client ? client.stop() : undefined;
}

module.exports = { activate, deactivate };
