//! The mutations of the examples shared by `tests/mutations.rs` and
//! `tests/lsp_sessions.rs`: the random scene generator's token-level mutations
//! (`gen::mutate`), byte-level edits (cuts, insertions, duplications, moves, flipped
//! bits, spliced lines, extreme numbers, deep nesting, chained calls) and mild edits
//! that often leave the scene valid (scaled numbers, seeds removed or moved, method
//! calls removed, other builtins, added settings). Every case comes from one seed.
#![allow(dead_code)]

use crate::gen::{self, Rng};
use std::path::{Path, PathBuf};

/// Edits left out because they hit a known bug; each entry says which. The in-suite
/// runs stay green while the bug is open; `SDFC_MUT_ALL=1` puts them back.
pub const KNOWN_BUGS: &[(&str, &str)] = &[];

/// Whether an inserted piece of text is left out (see [`KNOWN_BUGS`]).
fn excluded(piece: &str) -> bool {
    std::env::var_os("SDFC_MUT_ALL").is_none()
        && KNOWN_BUGS.iter().any(|(p, _)| piece.starts_with(p))
}

pub fn examples_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples")
}

/// The examples, sorted by name: (name, text).
pub fn examples() -> Vec<(String, String)> {
    let mut out: Vec<(String, String)> = std::fs::read_dir(examples_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "sdf"))
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read_to_string(&p).unwrap(),
            )
        })
        .collect();
    out.sort();
    assert!(out.len() >= 10, "{} examples", out.len());
    out
}

// ------------------------------------------------------------------ the mutations

/// One mutated example.
#[derive(Debug, Clone)]
pub struct Case {
    pub seed: u64,
    pub example: String,
    pub kinds: Vec<&'static str>,
    pub text: String,
}

/// Pieces of text that the byte-level insertions put in: tokens of every kind, the
/// keywords and statements of atlas blocks, and a few bytes the lexer must survive.
const FRAGMENTS: &[&str] = &[
    "{",
    "}",
    "(",
    ")",
    "[",
    "]",
    ";",
    ",",
    ".",
    ":",
    "=",
    "|",
    "&",
    "-",
    "+",
    "*",
    "/",
    "%",
    "<",
    ">",
    "!",
    "?",
    "\"",
    "//",
    "/*",
    "*/",
    "#",
    "@",
    "\\",
    "let",
    "atlas",
    "material",
    "render",
    "on",
    "seed",
    "merge",
    "tangent",
    "true",
    "false",
    "pi",
    "position",
    "uv",
    " ",
    "\n",
    "\t",
    "\r\n",
    "\r",
    "\u{0}",
    "\u{feff}",
    "é",
    "😀",
    "\u{2028}",
    "0",
    "1.5",
    "-0",
    "1e38",
    "3.4e38",
    "1e-45",
    "1e400",
    "nan",
    "inf",
    "65536",
    "4294967296",
    "0.000000001",
    ".5",
    "5.",
    "1_000",
    "0x10",
];

/// Whole statements and items to insert (valid somewhere, wrong elsewhere).
const STATEMENTS: &[&str] = &[
    "seed q0 = [0, 0, 1];",
    "seed q1 = [0, 1, 0] tangent [1, 0, 0];",
    "seed q2 = [0, 0, 0] tangent [0, 0, 0];",
    "merge q0 q1;",
    "merge q0 q0;",
    "steps = 1;",
    "steps = 64;",
    "steps = 0;",
    "max_distance = 0;",
    "max_distance = 1e30;",
    "let q = sphere(1);",
    "let q = q;",
    "render q;",
    "render sphere(1e-30);",
    "render sphere(1e30);",
    "atlas qa on sphere(1) { seed a = [0, 0, 1]; }",
    "atlas qb on plane() { seed a = [0, 0, 0]; }",
    "atlas qc on box([1, 1, 1]) { }",
    "material qm { base_color = [1, 0, 0]; }",
    "let qt = image(\"textures/bricks.png\");",
    "let qt = image(\"textures/missing.png\");",
    "let qt = image(\"textures\");",
    "let qt = image(\"/etc/passwd\");",
    "let qt = image(\"../Cargo.toml\");",
];

/// Replacements for a number.
const NUMBERS: &[&str] = &[
    "0",
    "-0",
    "-1",
    "1e-30",
    "1e30",
    "3.4e38",
    "-3.4e38",
    "1e39",
    "1e-45",
    "1e-320",
    "0.5e0",
    "1000000",
    "64",
    "65",
    "256",
    "257",
    "4096",
    "0.0000001",
    "(0 / 0)",
    "(1 / 0)",
    "-(1 / 0)",
    "sqrt(-1)",
    "position.x",
    "[0, 0, 0]",
    "true",
];

pub fn lex(text: &str) -> Vec<(sdfc::syntax::lexer::Token<'_>, sdfc::Span)> {
    let mut d = Vec::new();
    sdfc::syntax::lexer::lex(text, &mut d).tokens
}

/// A random char boundary of `text` (0 ..= len).
pub fn boundary(rng: &mut Rng, text: &str) -> usize {
    let mut at = rng.below(text.len() + 1);
    while !text.is_char_boundary(at) {
        at -= 1;
    }
    at
}

/// A random range of `text` on char boundaries, at most `max` bytes long.
pub fn range(rng: &mut Rng, text: &str, max: usize) -> (usize, usize) {
    let a = boundary(rng, text);
    let mut b = (a + 1 + rng.below(max)).min(text.len());
    while !text.is_char_boundary(b) {
        b += 1;
    }
    (a, b)
}

/// The items of `text` (from one item keyword to the next) as byte ranges.
pub fn items(text: &str) -> Vec<(usize, usize)> {
    let starts: Vec<usize> = lex(text)
        .iter()
        .filter(|(t, _)| t.starts_item())
        .map(|(_, s)| s.start)
        .chain([text.len()])
        .collect();
    starts.windows(2).map(|w| (w[0], w[1])).collect()
}

/// One byte-level (or structure-blind) edit of `text`; `others` are the other
/// examples, for spliced lines.
pub fn byte_mutation(
    rng: &mut Rng,
    text: &str,
    others: &[(String, String)],
) -> (&'static str, String) {
    let splice = |a: usize, b: usize, with: &str| format!("{}{with}{}", &text[..a], &text[b..]);
    match rng.below(14) {
        0 => {
            let (a, b) = range(rng, text, 24);
            ("cut bytes", splice(a, b, ""))
        }
        1 => {
            let at = boundary(rng, text);
            let n = 1 + rng.below(3);
            let with: String = (0..n).map(|_| *rng.pick(FRAGMENTS)).collect();
            ("inserted fragments", splice(at, at, &with))
        }
        2 => {
            let (a, b) = range(rng, text, 80);
            let at = boundary(rng, text);
            let piece = text[a..b].to_string();
            ("duplicated bytes", splice(at, at, &piece))
        }
        3 => {
            // A range moved elsewhere.
            let (a, b) = range(rng, text, 80);
            let piece = text[a..b].to_string();
            let rest = splice(a, b, "");
            let mut at = rng.below(rest.len() + 1);
            while !rest.is_char_boundary(at) {
                at -= 1;
            }
            (
                "moved bytes",
                format!("{}{piece}{}", &rest[..at], &rest[at..]),
            )
        }
        4 => {
            // A flipped bit: may leave invalid UTF-8, which is replaced as `check` does.
            let mut bytes = text.as_bytes().to_vec();
            if !bytes.is_empty() {
                let k = rng.below(bytes.len());
                bytes[k] ^= 1 << rng.below(8);
            }
            ("flipped bit", sdfc::syntax::decode(&bytes).0)
        }
        5 => {
            let at = boundary(rng, text);
            ("truncated", text[..at].to_string())
        }
        6 => {
            let (_, other) = rng.pick(others);
            let lines: Vec<&str> = other.lines().collect();
            let line = lines[rng.below(lines.len())];
            let starts: Vec<usize> = std::iter::once(0)
                .chain(text.match_indices('\n').map(|(i, _)| i + 1))
                .collect();
            let at = starts[rng.below(starts.len())];
            ("spliced line", splice(at, at, &format!("{line}\n")))
        }
        7 => {
            let nums: Vec<sdfc::Span> = lex(text)
                .iter()
                .filter(|(t, _)| matches!(t, sdfc::syntax::lexer::Token::Number(_)))
                .map(|(_, s)| *s)
                .collect();
            if nums.is_empty() {
                return ("truncated", String::new());
            }
            let s = nums[rng.below(nums.len())];
            ("extreme number", splice(s.start, s.end, *rng.pick(NUMBERS)))
        }
        8 => {
            // A statement or item on a line of its own, or after a `;` or `{`.
            let stmt = *rng.pick(STATEMENTS);
            let anchors: Vec<usize> = text
                .match_indices([';', '{', '\n'])
                .map(|(i, _)| i + 1)
                .chain([0, text.len()])
                .collect();
            let at = anchors[rng.below(anchors.len())];
            ("inserted statement", splice(at, at, &format!(" {stmt}\n")))
        }
        9 => {
            // One name for another name of the text (well-formed, often mistyped).
            let ids: Vec<sdfc::Span> = lex(text)
                .iter()
                .filter(|(t, _)| matches!(t, sdfc::syntax::lexer::Token::Ident(_)))
                .map(|(_, s)| *s)
                .collect();
            if ids.len() < 2 {
                return ("truncated", String::new());
            }
            let s = ids[rng.below(ids.len())];
            let with = text[ids[rng.below(ids.len())].range()].to_string();
            ("swapped name", splice(s.start, s.end, &with))
        }
        10 => {
            let its = items(text);
            if its.is_empty() {
                return ("truncated", String::new());
            }
            let (a, b) = its[rng.below(its.len())];
            let piece = text[a..b].to_string();
            ("duplicated item", splice(b, b, &piece))
        }
        11 => {
            let its = items(text);
            if its.is_empty() {
                return ("truncated", String::new());
            }
            let (a, b) = its[rng.below(its.len())];
            ("removed item", splice(a, b, ""))
        }
        12 => {
            // Deep nesting where an expression may stand: after `=` or `(`.
            let anchors: Vec<usize> = text.match_indices(['=', '(']).map(|(i, _)| i + 1).collect();
            if anchors.is_empty() {
                return ("truncated", String::new());
            }
            let at = anchors[rng.below(anchors.len())];
            let depth = 1 + rng.below(400);
            let (open, close) = *rng.pick(&[("(", ")"), ("-", ""), ("[", "]"), ("!", "")]);
            let with = format!("{}1{} + ", open.repeat(depth), close.repeat(depth));
            ("deep nesting", splice(at, at, &with))
        }
        _ => {
            // A method call appended to a shape expression, many times over.
            let anchors: Vec<usize> = text.match_indices(')').map(|(i, _)| i + 1).collect();
            if anchors.is_empty() {
                return ("truncated", String::new());
            }
            let at = anchors[rng.below(anchors.len())];
            let call = *rng.pick(&[
                ".translate([0, 0.1, 0])",
                ".rotate([0, 1, 0], 0.3)",
                ".scale(1.01)",
                ".twist(0.1)",
                ".round(0.01)",
                ".shell(0.01)",
                ".mirror([1, 0, 0])",
                ".displace(0.01)",
            ]);
            let n = 1 + rng.below(40);
            ("chained calls", splice(at, at, &call.repeat(n)))
        }
    }
}

/// A number as the scene language writes it (no exponent for the usual magnitudes).
pub fn number(x: f64) -> String {
    if x == x.trunc() && x.abs() < 1e15 {
        format!("{}", x as i64)
    } else if (1e-4..1e15).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// The index of the token that closes the bracket opened at token `open`.
pub fn matching(
    toks: &[(sdfc::syntax::lexer::Token<'_>, sdfc::Span)],
    open: usize,
) -> Option<usize> {
    use sdfc::syntax::lexer::Token;
    let mut depth = 0i32;
    for (k, (t, _)) in toks.iter().enumerate().skip(open) {
        match t {
            Token::LParen | Token::LBracket | Token::LBrace => depth += 1,
            Token::RParen | Token::RBracket | Token::RBrace => {
                depth -= 1;
                if depth == 0 {
                    return Some(k);
                }
            }
            _ => {}
        }
    }
    None
}

/// One edit that often leaves the scene valid, so that the geometry, code generation
/// and seed placement see it: a number scaled, a seed or merge statement removed or
/// moved, a method call removed, a builtin for another of its kind, a setting added.
pub fn mild_mutation(rng: &mut Rng, text: &str) -> (&'static str, String) {
    use sdfc::syntax::lexer::Token;
    let toks = lex(text);
    let splice = |a: usize, b: usize, with: &str| format!("{}{with}{}", &text[..a], &text[b..]);
    let of = |f: &dyn Fn(&Token) -> bool| -> Vec<usize> {
        toks.iter()
            .enumerate()
            .filter(|(_, (t, _))| f(t))
            .map(|(k, _)| k)
            .collect()
    };
    for _ in 0..8 {
        match rng.below(7) {
            0 | 1 => {
                let nums = of(&|t| matches!(t, Token::Number(_)));
                if let Some(&k) = nums.get(rng.below(nums.len().max(1))) {
                    let s = toks[k].1;
                    let Ok(x) = text[s.range()].parse::<f64>() else {
                        continue;
                    };
                    let f = *rng.pick(&[
                        0.0, 1e-3, 0.25, 0.5, 0.9, 0.99, 1.01, 1.1, 2.0, 10.0, 1e3, 1e6,
                    ]);
                    return ("scaled number", splice(s.start, s.end, &number(x * f)));
                }
            }
            2 => {
                // A seed or merge statement removed.
                let kw = of(&|t| matches!(t, Token::Seed | Token::Merge));
                if let Some(&k) = kw.get(rng.below(kw.len().max(1))) {
                    let end = toks[k..]
                        .iter()
                        .find(|(t, _)| matches!(t, Token::Semi))
                        .map_or(text.len(), |(_, s)| s.end);
                    return ("removed seed statement", splice(toks[k].1.start, end, ""));
                }
            }
            3 => {
                // A seed moved to a random point near the origin.
                let seeds = of(&|t| matches!(t, Token::Seed));
                if let Some(&k) = seeds.get(rng.below(seeds.len().max(1))) {
                    let Some(open) = (k..toks.len())
                        .take_while(|&j| !matches!(toks[j].0, Token::Semi))
                        .find(|&j| matches!(toks[j].0, Token::LBracket))
                    else {
                        continue;
                    };
                    let Some(close) = matching(&toks, open) else {
                        continue;
                    };
                    let mut c = || number(((rng.unit() * 4.0 - 2.0) * 1e3).round() / 1e3);
                    let v = format!("[{}, {}, {}]", c(), c(), c());
                    return (
                        "moved seed",
                        splice(toks[open].1.start, toks[close].1.end, &v),
                    );
                }
            }
            4 => {
                // `.f(…)` removed.
                let dots: Vec<usize> = (0..toks.len().saturating_sub(2))
                    .filter(|&k| {
                        matches!(toks[k].0, Token::Dot)
                            && matches!(toks[k + 1].0, Token::Ident(_))
                            && matches!(toks[k + 2].0, Token::LParen)
                    })
                    .collect();
                if let Some(&k) = dots.get(rng.below(dots.len().max(1))) {
                    if let Some(close) = matching(&toks, k + 2) {
                        return (
                            "removed method call",
                            splice(toks[k].1.start, toks[close].1.end, ""),
                        );
                    }
                }
            }
            5 => {
                // A builtin's name for another builtin of its kind.
                use sdfc::sema::builtins::{lookup, BUILTINS};
                let calls = of(&|t| matches!(t, Token::Ident(n) if lookup(n).is_some()));
                if let Some(&k) = calls.get(rng.below(calls.len().max(1))) {
                    let Token::Ident(name) = toks[k].0 else {
                        continue;
                    };
                    let kind = lookup(name).unwrap().kind;
                    let same: Vec<&str> = BUILTINS
                        .iter()
                        .filter(|b| b.kind == kind)
                        .map(|b| b.name)
                        .collect();
                    let with = *rng.pick(&same);
                    let s = toks[k].1;
                    return ("other builtin", splice(s.start, s.end, with));
                }
            }
            _ => {
                // A setting added first in an atlas block, or after any statement.
                let opens: Vec<usize> = (0..toks.len())
                    .filter(|&k| matches!(toks[k].0, Token::Atlas))
                    .filter_map(|k| (k..toks.len()).find(|&j| matches!(toks[j].0, Token::LBrace)))
                    .collect();
                let semis = of(&|t| matches!(t, Token::Semi));
                let anchors = if !opens.is_empty() && rng.chance(0.7) {
                    opens
                } else {
                    semis
                };
                if let Some(&k) = anchors.get(rng.below(anchors.len().max(1))) {
                    let setting = *rng.pick(&[
                        "steps = 1;",
                        "steps = 2;",
                        "steps = 8;",
                        "steps = 64;",
                        "max_distance = 0.01;",
                        "max_distance = 100;",
                        "heuristic_tolerance = 0.5;",
                        "sharp_tolerance = 0.5;",
                        "sharp_tolerance = 1e-6;",
                        "min_reach = 1;",
                        "refine = 1;",
                        "refine = 8;",
                        "reproject = true;",
                        "sigma = 0.01;",
                        "sigma = 10;",
                        "mirror = [1, 0, 0];",
                        "mirror = [0, 1, 0];",
                        "mirror = [0, 0, -1];",
                        "mirror = [1, 1, 1];",
                        "roughness = 0.5;",
                        "metallic = 1;",
                    ]);
                    if excluded(setting) {
                        continue;
                    }
                    let at = toks[k].1.end;
                    return ("added setting", splice(at, at, &format!(" {setting}")));
                }
            }
        }
    }
    ("scaled number", text.to_string())
}

/// One token-level (`gen::mutate`) or byte-level edit; `others` are the examples,
/// for spliced lines.
pub fn rough_edit(
    rng: &mut Rng,
    text: &str,
    others: &[(String, String)],
) -> (&'static str, String) {
    if rng.chance(0.5) && !text.is_empty() {
        gen::mutate(rng, text)
    } else {
        byte_mutation(rng, text, others)
    }
}

/// Case `seed`: one to three edits of one example (by turns): mild ones only, or
/// token-level (`gen::mutate`) and byte-level ones.
pub fn case(seed: u64, examples: &[(String, String)]) -> Case {
    let mut rng = Rng::new(seed);
    let (name, original) = &examples[(seed % examples.len() as u64) as usize];
    let mut text = original.clone();
    let mut kinds = Vec::new();
    let edits = *rng.pick(&[1, 1, 1, 2, 2, 3]);
    // Two cases in five are mild edits only (see `mild_mutation`).
    let mild = rng.chance(0.4);
    for _ in 0..edits {
        let (kind, t) = if mild {
            mild_mutation(&mut rng, &text)
        } else {
            rough_edit(&mut rng, &text, examples)
        };
        kinds.push(kind);
        text = t;
    }
    Case {
        seed,
        example: name.clone(),
        kinds,
        text,
    }
}
