//! The formatter: examples are formatted, formatting is idempotent and keeps
//! every token and comment, files with syntax errors are refused.

use sdfc::ide::format::{format, minimal_edit};
use sdfc::syntax::lexer::lex;
use std::path::Path;

const MESSY: &str = "// header comment
let  a=sphere( 1 )  ;let b = box([1,2,3]).translate( [ 0,-1 , 0 ] );   // trailing
/* block
   comment */



let c = a|b   &   -a; let d = smooth_union(a,b,k:0.1);
atlas skin on c { steps=10; // N
seed front=[0,0,1] tangent [1,0,0]; // first
seed top = [0,1,0];
  merge front top;}
material m {color = [skin.uv, 0]*(1-0.5); roughness = 0.5;}
material empty {}
let long = union(a,
  b /* inline */)
  | c;
render c.paint(m);
";

fn sdf_files(dir: &str) -> Vec<std::path::PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join(dir);
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "sdf"))
        .collect();
    files.sort();
    files
}

/// The significant tokens and the comments (without trailing whitespace) of a text.
fn tokens(text: &str) -> (Vec<String>, Vec<String>) {
    let lexed = lex(text, &mut Vec::new());
    (
        lexed
            .tokens
            .iter()
            .map(|(_, s)| text[s.range()].to_string())
            .collect(),
        lexed
            .comments
            .iter()
            .map(|c| text[c.span.range()].trim_end().replace("\r\n", "\n"))
            .collect(),
    )
}

#[test]
fn formats_a_messy_file() {
    let out = format(MESSY).unwrap();
    insta::with_settings!({ snapshot_path => "../snapshots", prepend_module_to_snapshot => false, omit_expression => true }, {
        insta::assert_snapshot!("format_messy", out);
    });
    assert_eq!(format(&out).unwrap(), out, "not idempotent");
    assert_eq!(tokens(&out), tokens(MESSY));
    for c in [
        "// header comment",
        "// trailing",
        "/* block\n   comment */",
        "// N",
        "// first",
        "/* inline */",
    ] {
        assert!(out.contains(c), "lost {c:?}:\n{out}");
    }
}

#[test]
fn every_example_is_formatted() {
    let files = sdf_files("examples");
    assert!(files.len() >= 5);
    for path in files {
        let src = std::fs::read_to_string(&path).unwrap();
        let out = format(&src).unwrap_or_else(|d| panic!("{}: {d:?}", path.display()));
        assert!(
            out == src,
            "{} is not formatted; it would become:\n{out}",
            path.display()
        );
    }
}

#[test]
fn idempotent_and_lossless_on_every_ui_case() {
    let (mut formatted, mut refused) = (0, 0);
    for path in sdf_files("tests/ui") {
        let src = std::fs::read_to_string(&path).unwrap();
        match format(&src) {
            Ok(once) => {
                formatted += 1;
                let twice = format(&once).unwrap_or_else(|d| panic!("{}: {d:?}", path.display()));
                assert_eq!(twice, once, "{} is not idempotent", path.display());
                assert_eq!(
                    tokens(&once),
                    tokens(&src),
                    "{} lost tokens",
                    path.display()
                );
                // Formatting never changes what the checker says.
                let codes = |t: &str| -> Vec<&'static str> {
                    sdfc::driver::analyze(t, path.parent())
                        .diagnostics
                        .iter()
                        .map(|d| d.code)
                        .collect()
                };
                assert_eq!(codes(&once), codes(&src), "{}", path.display());
            }
            Err(diags) => {
                refused += 1;
                assert!(diags.iter().all(|d| d.is_error()), "{}", path.display());
            }
        }
    }
    assert!(formatted >= 40, "only {formatted} UI cases formatted");
    assert!(refused >= 8, "only {refused} UI cases refused");
}

#[test]
fn syntax_errors_are_not_formatted() {
    let diags = format("let a = sphere(1)\nlet b = box(1);\n").unwrap_err();
    assert_eq!(diags.len(), 1);
    assert_eq!(diags[0].code, "E0010");
    assert!(format("let a = \"open;\n").is_err());
    assert!(format("let a = 1; /* never closed").is_err());
}

#[test]
fn crlf_and_empty_files() {
    assert_eq!(format("").unwrap(), "");
    assert_eq!(
        format("\n\n  // only a comment  \n\n").unwrap(),
        "// only a comment\n"
    );
    assert_eq!(
        format("let a=1;\r\n\r\n\r\nlet b=2; // two\r\n").unwrap(),
        "let a = 1;\r\n\r\nlet b = 2;  // two\r\n"
    );
}

#[test]
fn trailing_comments_align_and_blocks_indent() {
    let src = "atlas s on b {\nsteps = 20; // N\nmax_distance = 3.0;   // D\n\nseed x = [0, 0, 1]; // alone\n}\n";
    assert_eq!(
        format(src).unwrap(),
        "atlas s on b {\n    steps = 20;          // N\n    max_distance = 3.0;  // D\n\n    seed x = [0, 0, 1];  // alone\n}\n"
    );
    assert_eq!(
        format("render a.b(-1, !c, [-2, x - 3]) {}").unwrap(),
        "render a.b(-1, !c, [-2, x - 3]) {}\n"
    );
    // A `{` after a comment gets its own line, level with its `}`.
    assert_eq!(
        format("atlas a on b // why\n{\n  seed x = [0,0,1]\n     tangent [1,0,0];\n}").unwrap(),
        "atlas a on b  // why\n{\n    seed x = [0, 0, 1]\n        tangent [1, 0, 0];\n}\n"
    );
}

#[test]
fn minimal_edits() {
    assert_eq!(minimal_edit("abc", "abc"), None);
    let (span, text) = minimal_edit("let a=1;\n", "let a = 1;\n").unwrap();
    assert_eq!((span.start, span.end, text.as_str()), (5, 6, " = "));
    let (span, text) = minimal_edit("é=1", "é = 1").unwrap();
    assert_eq!((span.start, span.end, text.as_str()), (2, 3, " = "));
}

/// Re-spaces every file (random whitespace between tokens, newlines after line
/// comments): the result formats, idempotently, to the same tokens and comments.
#[test]
fn any_spacing_formats_idempotently() {
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    let gaps = [" ", "  ", "\n", "\n\n\n", "\t", " \n    "];
    let mut files = sdf_files("examples");
    files.extend(sdf_files("tests/ui"));
    let mut checked = 0;
    for path in files {
        let src = std::fs::read_to_string(&path).unwrap();
        if format(&src).is_err() {
            continue;
        }
        let lexed = lex(&src, &mut Vec::new());
        let mut pieces: Vec<(usize, usize, bool)> = lexed
            .tokens
            .iter()
            .map(|(_, s)| (s.start, s.end, false))
            .chain(
                lexed
                    .comments
                    .iter()
                    .map(|c| (c.span.start, c.span.end, !c.block)),
            )
            .collect();
        pieces.sort();
        for _ in 0..4 {
            let mut text = String::new();
            for &(start, end, line_comment) in &pieces {
                text.push_str(src[start..end].trim_end());
                let gap = gaps[(next() % gaps.len() as u64) as usize];
                text.push_str(if line_comment && !gap.contains('\n') {
                    "\n"
                } else {
                    gap
                });
            }
            let once =
                format(&text).unwrap_or_else(|d| panic!("{}: {d:?}\n{text}", path.display()));
            assert_eq!(format(&once).unwrap(), once, "{}:\n{text}", path.display());
            assert_eq!(tokens(&once), tokens(&src), "{}", path.display());
            checked += 1;
        }
    }
    assert!(checked >= 150, "{checked}");
}
