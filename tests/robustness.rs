//! The front end never panics: every prefix of every example (cut at every byte),
//! random byte edits, and pathological inputs all come back as diagnostics.

use sdfc::driver::analyze;
use std::path::Path;

fn examples() -> Vec<(String, Vec<u8>)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut out: Vec<(String, Vec<u8>)> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "sdf"))
        .map(|p| (p.display().to_string(), std::fs::read(&p).unwrap()))
        .collect();
    out.sort();
    out
}

/// Every diagnostic's spans lie inside the text, so renderers and editors can use them.
fn check_no_panic(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    let analysis = analyze(&text, None);
    for d in &analysis.diagnostics {
        for l in d.primary.iter().chain(&d.secondary) {
            assert!(
                l.span.start <= l.span.end && l.span.end <= text.len(),
                "span {:?} outside text of {} bytes",
                l.span,
                text.len()
            );
        }
    }
    // Rendering must not panic either.
    let _ = sdfc::diagnostic::render("fuzz.sdf", &text, &analysis.diagnostics, false);
}

#[test]
fn every_prefix_of_every_example() {
    for (_, bytes) in examples() {
        for cut in 0..=bytes.len() {
            check_no_panic(&bytes[..cut]);
        }
    }
}

/// A small deterministic generator (xorshift64*), so failures reproduce.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

#[test]
fn random_byte_edits() {
    let interesting: &[u8] = b"()[]{};,.:=+-*/%|&!<>\"/\n 0123456789eE.abcxyz_\xff\xc3";
    let mut rng = Rng(0x5DF0_2026);
    let mut runs = 0;
    for (_, original) in examples() {
        for _ in 0..150 {
            let mut bytes = original.clone();
            for _ in 0..1 + rng.below(6) {
                let at = rng.below(bytes.len() + 1);
                match rng.below(4) {
                    0 if at < bytes.len() => {
                        bytes.remove(at);
                    }
                    1 => bytes.insert(at, interesting[rng.below(interesting.len())]),
                    2 if at < bytes.len() => bytes[at] = interesting[rng.below(interesting.len())],
                    _ => {
                        // Duplicate a slice: repeats items, statements and brackets.
                        let end = (at + rng.below(40)).min(bytes.len());
                        let piece = bytes[at..end].to_vec();
                        let to = rng.below(bytes.len() + 1);
                        bytes.splice(to..to, piece);
                    }
                }
            }
            check_no_panic(&bytes);
            runs += 1;
        }
    }
    assert!(runs >= 300, "only {runs} random edits ran");
}

#[test]
fn pathological_inputs() {
    let deep_parens = format!("let a = {}1{};", "(".repeat(5000), ")".repeat(5000));
    let deep_unclosed = format!("let a = {}", "[".repeat(20000));
    let long_chain = format!("let a = 1{};\nrender sphere(a);", " + 1".repeat(5000));
    let long_union = format!("render sphere(1){};", " | sphere(1)".repeat(2000));
    let many_neg = format!("let a = {}1;", "-".repeat(5000));
    let method_chain = format!("render sphere(1){};", ".translate([0, 0, 0])".repeat(2000));
    for input in [
        deep_parens,
        deep_unclosed,
        long_chain,
        long_union,
        many_neg,
        method_chain,
        String::from("\u{0}\u{feff}"),
        "\"".repeat(3),
        "/*".into(),
        "let".into(),
    ] {
        check_no_panic(input.as_bytes());
    }
}

#[test]
fn deep_nesting_is_reported_not_crashed() {
    let limit = sdfc::syntax::parser::MAX_NESTING;
    let src = format!(
        "let a = {}1{};",
        "(".repeat(limit + 1),
        ")".repeat(limit + 1)
    );
    let analysis = analyze(&src, None);
    assert!(analysis
        .diagnostics
        .iter()
        .any(|d| d.code == sdfc::codes::E_TOO_DEEP));
    // Just inside the limit is fine.
    let src = format!("let _a = {}1{};", "(".repeat(limit), ")".repeat(limit));
    let analysis = analyze(&src, None);
    assert!(
        analysis.diagnostics.is_empty(),
        "{:?}",
        analysis.diagnostics
    );
}

/// The language server runs the whole pipeline on every edit: random numeric edits keep
/// most scenes valid, so the compile-time geometry, code generation and naga run on
/// odd inputs (seeds off the shape, zero sizes, huge distances). None may panic, and
/// naga must accept every module generated (an E0900 here is a code generator bug).
#[test]
fn numeric_edits_through_geometry_codegen_and_naga() {
    let mut rng = Rng(0x0C0D_E6E0);
    let mut valid = 0;
    for (name, original) in examples() {
        for _ in 0..6 {
            let mut bytes = original.clone();
            let digits: Vec<usize> = (0..bytes.len())
                .filter(|&i| bytes[i].is_ascii_digit())
                .collect();
            for _ in 0..1 + rng.below(3) {
                let at = digits[rng.below(digits.len())];
                bytes[at] = b"0123456789"[rng.below(10)];
            }
            let text = String::from_utf8(bytes).unwrap();
            let analysis = sdfc::driver::check_all(&text, Some(Path::new("examples")));
            valid += usize::from(!analysis.has_errors());
            for d in &analysis.diagnostics {
                assert_ne!(d.code, sdfc::codes::E_INTERNAL, "{name}: {d:#?}\n{text}");
                assert!(d.span().is_some_and(|s| s.end <= text.len()), "{d:#?}");
            }
        }
    }
    assert!(valid >= 20, "only {valid} edited scenes were valid");
}
