#!/bin/sh
# Seeds each fuzz target's corpus (fuzz/corpus/TARGET) from the examples and the UI
# scenes; the language-server target gets them as documents (`#` + scene) and as framed
# messages. Run from anywhere; existing corpus files are kept.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(dirname "$here")
for t in parse check check_all format lsp; do
    mkdir -p "$here/corpus/$t"
done
for f in "$root"/examples/*.sdf "$root"/tests/ui/*.sdf; do
    name=$(basename "$f" .sdf)
    for t in parse check check_all format; do
        cp "$f" "$here/corpus/$t/$name"
    done
    { printf '#'; cat "$f"; } > "$here/corpus/lsp/doc-$name"
done
# Framed JSON-RPC: a didOpen of a small scene, a hover, shutdown and exit.
frame() {
    printf 'Content-Length: %s\r\n\r\n%s' "$(printf '%s' "$1" | wc -c | tr -d ' ')" "$1"
}
{
    frame '{"jsonrpc":"2.0","method":"textDocument/didOpen","params":{"textDocument":{"uri":"file:///fuzz/a.sdf","languageId":"sdf","version":1,"text":"let s = sphere(1);\nrender s;\n"}}}'
    frame '{"jsonrpc":"2.0","id":2,"method":"textDocument/hover","params":{"textDocument":{"uri":"file:///fuzz/a.sdf"},"position":{"line":0,"character":9}}}'
    frame '{"jsonrpc":"2.0","id":3,"method":"textDocument/completion","params":{"textDocument":{"uri":"file:///fuzz/a.sdf"},"position":{"line":1,"character":8}}}'
    frame '{"jsonrpc":"2.0","id":4,"method":"shutdown"}'
    frame '{"jsonrpc":"2.0","method":"exit"}'
} > "$here/corpus/lsp/framed-session"
echo "seeded $(ls "$here"/corpus/* | wc -l) corpus entries in $here/corpus"
