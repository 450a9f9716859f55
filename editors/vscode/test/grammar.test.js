// Tokenizes examples/*.sdf and hand-written lines with the TextMate grammar
// (grammar/sdf.tmLanguage.json, or the file SDF_GRAMMAR names) through
// vscode-textmate and vscode-oniguruma, the engine VS Code uses, and checks
// the scopes.
"use strict";

const { test, before } = require("node:test");
const assert = require("node:assert/strict");
const fs = require("node:fs");
const path = require("node:path");
const vsctm = require("vscode-textmate");
const oniguruma = require("vscode-oniguruma");

const REPO = path.resolve(__dirname, "..", "..", "..");
const GRAMMAR_PATH = process.env.SDF_GRAMMAR
  ? path.resolve(process.env.SDF_GRAMMAR)
  : path.join(REPO, "grammar", "sdf.tmLanguage.json");
const EXAMPLES = path.join(REPO, "examples");

const RAW = JSON.parse(fs.readFileSync(GRAMMAR_PATH, "utf8"));
/** Every keyword, from the grammar's `keywords` rule (tests/grammar.rs checks it against the lexer). */
const KEYWORDS = /^\\b\((.*)\)\\b$/.exec(RAW.repository.keywords.match)[1].split("|");

let onigLib;

before(async () => {
  const wasm = fs.readFileSync(require.resolve("vscode-oniguruma/release/onig.wasm"));
  await oniguruma.loadWASM(wasm.buffer.slice(wasm.byteOffset, wasm.byteOffset + wasm.byteLength));
  onigLib = {
    createOnigScanner: (patterns) => new oniguruma.OnigScanner(patterns),
    createOnigString: (s) => new oniguruma.OnigString(s),
  };
});

async function loadGrammar(raw) {
  const registry = new vsctm.Registry({
    onigLib: Promise.resolve(onigLib),
    loadGrammar: async (scopeName) =>
      scopeName === raw.scopeName ? vsctm.parseRawGrammar(JSON.stringify(raw), "sdf.tmLanguage.json") : null,
  });
  return registry.loadGrammar(raw.scopeName);
}

/** Tokens of each line: { line, start, end, text, scopes }. */
function tokenize(grammar, text) {
  const lines = text.split(/\r?\n/);
  let state = vsctm.INITIAL;
  return lines.map((line, index) => {
    const result = grammar.tokenizeLine(line, state);
    state = result.ruleStack;
    return result.tokens.map((t) => ({
      line: index,
      start: t.startIndex,
      end: Math.min(t.endIndex, line.length),
      text: line.slice(t.startIndex, Math.min(t.endIndex, line.length)),
      scopes: t.scopes,
    }));
  });
}

/** The token covering column `column` of line `line`. */
function tokenAt(tokens, line, column) {
  const found = tokens[line].find((t) => t.start <= column && column < t.end);
  assert.ok(found, `no token at ${line}:${column}`);
  return found;
}

/** The token that starts the `nth` occurrence of `needle` in the text (lines joined by \n). */
function tokenOf(tokens, text, needle, nth = 0) {
  const lines = text.split("\n");
  let seen = 0;
  for (let line = 0; line < lines.length; line++) {
    let from = 0;
    for (;;) {
      const column = lines[line].indexOf(needle, from);
      if (column < 0) break;
      if (seen++ === nth) return tokenAt(tokens, line, column);
      from = column + 1;
    }
  }
  assert.fail(`\`${needle}\` (occurrence ${nth}) is not in the text`);
}

const has = (token, prefix) => token.scopes.some((s) => s === prefix || s.startsWith(prefix + "."));
function assertScope(token, prefix, what) {
  assert.ok(has(token, prefix), `${what}: \`${token.text}\` at ${token.line}:${token.start} has ${token.scopes.join(" ")}, not ${prefix}`);
}
function assertNoScope(token, prefix, what) {
  assert.ok(!has(token, prefix), `${what}: \`${token.text}\` at ${token.line}:${token.start} has ${token.scopes.join(" ")}`);
}

const SCENE = [
  /* 0 */ "let s = sphere(0.5).translate([0, 1, 0]).rotate_x(90deg);",
  /* 1 */ "atlas skin on s {",
  /* 2 */ "    steps = 12;",
  /* 3 */ "    seed a = [0, 0.5, 0] tangent [1, 0, 0];",
  /* 4 */ "    seed b = [0, -0.5, 0];",
  /* 5 */ "    merge a b;",
  /* 6 */ "}",
  /* 7 */ 'let tex = image("wood \\"oak\\".png"); // a texture',
  /* 8 */ "material m { color = [skin.uv, 0] * tex.sample(skin.uv).rgb; emission = 2.5e-3 * pi; }",
  /* 9 */ "let after = mirror(s, normal: [1, 0, 0]) | box(1); /* block",
  /* 10 */ "   comment */ render after { shadows = true; }",
  /* 11 */ "let next = 1.5rad;",
  /* 12 */ "let stray = [1 : 2]; // a colon outside a named argument (a syntax error)",
].join("\n");

/** Strings that reach the end of their line (the lexer's UnterminatedStr), each followed by code. */
const UNTERMINATED = [
  /* 0 */ 'let broken = "no closing quote',
  /* 1 */ "let after = mirror(s, normal: [1, 0, 0]) | box(1);",
  /* 2 */ 'let ends_in_backslash = "abc\\',
  /* 3 */ "let next = 1.5rad;",
].join("\n");

test("method calls are scoped as functions, fields as members", async () => {
  const tokens = tokenize(await loadGrammar(RAW), SCENE);
  for (const [name, nth] of [["sphere", 0], ["translate", 0], ["rotate_x", 0], ["sample", 0], ["mirror", 0], ["box", 0], ["image", 0]]) {
    const token = tokenOf(tokens, SCENE, name, nth);
    assert.equal(token.text, name);
    assertScope(token, "entity.name.function", name);
    assertNoScope(token, "variable", name);
  }
  assertScope(tokenOf(tokens, SCENE, ".translate"), "punctuation.accessor", "the dot of .translate");
  assertScope(tokenOf(tokens, SCENE, "translate"), "meta.function-call", "translate");
  // `skin.uv` and the swizzle `.rgb` are fields, not calls.
  for (const [name, nth] of [["uv", 0], ["uv", 1], ["rgb", 0]]) {
    const token = tokenOf(tokens, SCENE, name, nth);
    assertScope(token, "variable.other.member", name);
    assertNoScope(token, "entity.name.function", name);
  }
});

test("item keywords are control keywords, the other keywords are keywords, true and false constants", async () => {
  const tokens = tokenize(await loadGrammar(RAW), SCENE);
  for (const word of ["let", "atlas", "material", "render"]) {
    assertScope(tokenOf(tokens, SCENE, word + " "), "keyword.control", word);
  }
  for (const word of ["on", "seed", "tangent", "merge"]) {
    const token = tokenOf(tokens, SCENE, word + " ");
    assert.equal(token.text, word);
    assertScope(token, "keyword.other", word);
    assertNoScope(token, "keyword.control", word);
  }
  assertScope(tokenOf(tokens, SCENE, "true"), "constant.language.boolean", "true");
  // Every keyword on its own gets a keyword or constant scope.
  const grammar = await loadGrammar(RAW);
  for (const word of KEYWORDS) {
    const [token] = tokenize(grammar, word)[0];
    assert.equal(token.text, word);
    assert.ok(has(token, "keyword") || has(token, "constant.language"), `${word}: ${token.scopes.join(" ")}`);
  }
  // Names that only contain a keyword are not keywords.
  const [token] = tokenize(grammar, "let on_top = seeded;")[0].filter((t) => t.text === "on_top");
  assertNoScope(token, "keyword", "on_top");
});

test("an unterminated string ends at the end of its line, as the lexer's does", async () => {
  const tokens = tokenize(await loadGrammar(RAW), UNTERMINATED);
  assertScope(tokenOf(tokens, UNTERMINATED, '"no closing'), "string.quoted.double", "the unterminated string");
  assertScope(tokenOf(tokens, UNTERMINATED, "quote"), "string.quoted.double", "the unterminated string's end");
  assertScope(tokenOf(tokens, UNTERMINATED, '"abc'), "string.quoted.double", "the string ending in a backslash");
  for (const line of [1, 3]) {
    for (const token of tokens[line]) assertNoScope(token, "string", `line ${line} after an unterminated string`);
    assertScope(tokens[line][0], "keyword.control", `\`let\` on line ${line}, after an unterminated string`);
  }
  assertScope(tokenOf(tokens, UNTERMINATED, "mirror"), "entity.name.function", "mirror after the unterminated string");
  assertScope(tokenOf(tokens, UNTERMINATED, "1.5"), "constant.numeric", "a number after the unterminated string");
  // A closed string with escaped quotes ends at its closing quote.
  const scene = tokenize(await loadGrammar(RAW), SCENE);
  assertScope(tokenOf(scene, SCENE, '\\"oak'), "constant.character.escape", "escaped quote");
  assertScope(tokenOf(scene, SCENE, '"); //'), "punctuation.definition.string.end", "closing quote");
  assertNoScope(tokenOf(scene, SCENE, '); //'), "string", "after the closing quote");
});

test("comments and numbers", async () => {
  const tokens = tokenize(await loadGrammar(RAW), SCENE);
  assertScope(tokenOf(tokens, SCENE, "// a texture"), "comment.line.double-slash", "line comment");
  assertScope(tokenOf(tokens, SCENE, "/* block"), "comment.block", "block comment start");
  assertScope(tokens[10][0], "comment.block", "block comment on its second line");
  assertNoScope(tokenOf(tokens, SCENE, "render after"), "comment", "after the block comment");
  for (const [number, nth] of [["0.5", 0], ["12", 0], ["2.5e-3", 0], ["90", 0], ["1.5", 0]]) {
    const token = tokenOf(tokens, SCENE, number, nth);
    assertScope(token, "constant.numeric", number);
  }
  assertScope(tokenOf(tokens, SCENE, "deg"), "keyword.other.unit", "deg");
  assertScope(tokenOf(tokens, SCENE, "rad"), "keyword.other.unit", "rad");
  assertScope(tokenOf(tokens, SCENE, "pi;"), "support.constant", "pi");
  // A named argument whose name is also a builtin (`normal`) is a parameter.
  assertScope(tokenOf(tokens, SCENE, "normal:"), "variable.parameter", "normal:");
  assertScope(tokenOf(tokens, SCENE, "steps"), "variable.other.property", "steps =");
});

/**
 * For each line of `text`, the [start, end) columns of its comments and strings,
 * found the way the lexer finds them: `//` to the end of the line, block
 * comments across lines up to the first star-slash, strings from `"` to the
 * next unescaped `"` or the end of the line.
 */
function lexicalSpans(text) {
  const lines = text.split(/\r?\n/);
  let inBlock = false;
  return lines.map((line) => {
    const spans = [];
    let i = 0;
    let start = 0;
    while (i < line.length) {
      if (inBlock) {
        const close = line.indexOf("*/", i);
        if (close < 0) break;
        spans.push([start, close + 2]);
        inBlock = false;
        i = close + 2;
      } else if (line.startsWith("//", i)) {
        spans.push([i, line.length]);
        i = line.length;
      } else if (line.startsWith("/*", i)) {
        inBlock = true;
        start = i;
        i += 2;
      } else if (line[i] === '"') {
        const m = /^"(?:[^"\\]|\\.)*"?/.exec(line.slice(i));
        spans.push([i, i + m[0].length]);
        i += m[0].length;
      } else {
        i++;
      }
    }
    if (inBlock) {
      spans.push([start, line.length]);
      start = 0;
    }
    return spans;
  });
}

test("every example: calls are functions, keywords are keywords, numbers are numbers, comments are comments", async () => {
  const grammar = await loadGrammar(RAW);
  const files = fs.readdirSync(EXAMPLES).filter((f) => f.endsWith(".sdf"));
  assert.ok(files.length >= 5, `examples: ${files}`);
  let calls = 0;
  for (const file of files) {
    const text = fs.readFileSync(path.join(EXAMPLES, file), "utf8");
    const tokens = tokenize(grammar, text);
    const spans = lexicalSpans(text);
    text.split(/\r?\n/).forEach((line, index) => {
      const where = `${file}:${index + 1}`;
      const skips = spans[index];
      const inSkip = (column) => skips.some(([a, b]) => a <= column && column < b);
      for (const [a] of skips) {
        const token = tokenAt(tokens, index, a);
        assert.ok(has(token, "comment") || has(token, "string"), `${where}: ${token.text} ${token.scopes.join(" ")}`);
      }
      for (const m of line.matchAll(/\b([A-Za-z_][A-Za-z0-9_]*)\s*\(/g)) {
        if (inSkip(m.index) || KEYWORDS.includes(m[1])) continue; // `render (a | b)` is no call
        assertScope(tokenAt(tokens, index, m.index), "entity.name.function", `${where}: call`);
        calls++;
      }
      for (const m of line.matchAll(new RegExp(`(?<![.\\w])(?:${KEYWORDS.join("|")})\\b`, "g"))) {
        if (inSkip(m.index)) continue;
        const token = tokenAt(tokens, index, m.index);
        assert.equal(token.text, m[0], where);
        assert.ok(has(token, "keyword") || has(token, "constant.language"), `${where}: ${m[0]} ${token.scopes.join(" ")}`);
      }
      for (const m of line.matchAll(/(?<![\w.])[0-9]+(?:\.[0-9]+)?(?:[eE][+-]?[0-9]+)?/g)) {
        if (inSkip(m.index)) continue;
        assertScope(tokenAt(tokens, index, m.index), "constant.numeric", `${where}: ${m[0]}`);
      }
      // Nothing outside a string is string-scoped (strings never run on).
      for (const token of tokens[index]) {
        if (!inSkip(token.start)) assertNoScope(token, "string", where);
      }
    });
  }
  assert.ok(calls > 50, `only ${calls} calls in the examples`);
});

/**
 * The grammar with a marker scope, `meta.rule.NAME` (or `meta.rule.NAME.I` for the
 * I-th pattern of a group), added to each rule of the repository.
 */
function markRules(raw) {
  const copy = JSON.parse(JSON.stringify(raw));
  const markers = [];
  const mark = (rule, marker) => {
    rule.name = rule.name ? `${rule.name} ${marker}` : marker;
    markers.push(marker);
  };
  for (const [name, rule] of Object.entries(copy.repository)) {
    if (rule.match || rule.begin) mark(rule, `meta.rule.${name}`);
    else (rule.patterns || []).forEach((p, i) => (p.match || p.begin) && mark(p, `meta.rule.${name}.${i}`));
  }
  return { raw: copy, markers };
}

test("every rule of the grammar matches something in the examples and the lines above", async () => {
  const { raw, markers } = markRules(RAW);
  const grammar = await loadGrammar(raw);
  const seen = new Set();
  const texts = [SCENE, UNTERMINATED, ...fs.readdirSync(EXAMPLES).filter((f) => f.endsWith(".sdf")).map((f) => fs.readFileSync(path.join(EXAMPLES, f), "utf8"))];
  for (const text of texts) {
    for (const line of tokenize(grammar, text)) for (const t of line) t.scopes.forEach((s) => seen.add(s));
  }
  const never = markers.filter((m) => !seen.has(m));
  assert.deepEqual(never, [], `rules that never match (shadowed by an earlier rule?): ${never.join(", ")}`);
  // Each top-level include names a rule that exists.
  for (const { include } of RAW.patterns) {
    assert.ok(RAW.repository[include.replace(/^#/, "")], include);
  }
});
