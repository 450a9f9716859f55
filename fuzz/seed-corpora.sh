#!/bin/sh
# Seeds each fuzz target's corpus (fuzz/corpus/TARGET) from the examples and the UI
# scenes; the language-server and seeds_write targets get them as documents (`#` +
# scene), the former also as framed messages; the glb target gets the .glb files of
# the repository, if any, and a small bake of the sphere when sdfc is built (release).
# Run from anywhere; existing corpus files are kept.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(dirname "$here")
for t in parse check check_all format lsp seeds_write glb; do
    mkdir -p "$here/corpus/$t"
done
for f in "$root"/examples/*.sdf "$root"/tests/ui/*.sdf; do
    name=$(basename "$f" .sdf)
    for t in parse check check_all format; do
        cp "$f" "$here/corpus/$t/$name"
    done
    { printf '#'; cat "$f"; } > "$here/corpus/lsp/doc-$name"
    { printf '#'; cat "$f"; } > "$here/corpus/seeds_write/doc-$name"
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
if [ -x "$root/target/release/sdfc" ]; then
    (cd "$root" && NODEVICE_SELECT=1 target/release/sdfc bake examples/sphere.sdf --grid 8 --size 64 -o "$here/corpus/glb/sphere.glb" >/dev/null 2>&1) || true
fi
echo "seeded $(ls "$here"/corpus/* | wc -l) corpus entries in $here/corpus"
