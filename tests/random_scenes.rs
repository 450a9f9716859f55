//! Random well-typed scenes (tests/gen) through the whole check: parse, check, the
//! atlas geometry, lowering, code generation and naga validation
//! (`sdfc::driver::check_all`). Each scene must come back without a panic, without an
//! internal compiler error (`E0900`), with every span inside the text, and in time.
//!
//! A failure names its seed; `SDFC_GEN_SEED=N cargo test --test random_scenes one_seed
//! -- --nocapture` prints that scene and its diagnostics. The 10,000-scene run is
//! `cargo test --release --test random_scenes -- --ignored`.

mod gen;

use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::sync::{Mutex, Once};
use std::time::{Duration, Instant};

/// A scene that takes longer than this is reported as a hang.
const HANG: Duration = Duration::from_secs(10);

/// How one scene went.
#[derive(Debug, Clone, PartialEq)]
enum Outcome {
    /// Diagnostics codes (errors first) and whether any is an error.
    Ok {
        errors: bool,
        codes: Vec<&'static str>,
        /// The first error, for the statistics.
        first_error: Option<String>,
    },
    Panic(String),
    Internal(String),
    BadSpan(String),
    Hang,
}

impl Outcome {
    fn is_failure(&self) -> bool {
        !matches!(self, Outcome::Ok { .. })
    }
    /// What must stay the same while a failing scene is shrunk.
    fn kind(&self) -> String {
        match self {
            Outcome::Ok { .. } => "ok".into(),
            // The panic's message without numbers (values change as the scene shrinks).
            Outcome::Panic(m) => format!(
                "panic {}",
                m.lines()
                    .next()
                    .unwrap_or("")
                    .replace(|c: char| c.is_ascii_digit(), "")
            ),
            // The naga error without line numbers or names.
            Outcome::Internal(m) => format!(
                "E0900 {}",
                m.split(" / at line")
                    .next()
                    .unwrap_or("")
                    .replace(|c: char| c.is_ascii_digit(), "")
            ),
            Outcome::BadSpan(_) => "span".into(),
            Outcome::Hang => "hang".into(),
        }
    }
}

static LAST_PANIC: Mutex<Option<String>> = Mutex::new(None);

/// Panics are caught per scene; the hook keeps the message and place, quietly.
fn quiet_panics() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        std::panic::set_hook(Box::new(|info| {
            let msg = if let Some(s) = info.payload().downcast_ref::<&str>() {
                s.to_string()
            } else if let Some(s) = info.payload().downcast_ref::<String>() {
                s.clone()
            } else {
                "(a panic without a message)".to_string()
            };
            let place = info
                .location()
                .map(|l| format!(" at {}:{}", l.file(), l.line()))
                .unwrap_or_default();
            *LAST_PANIC.lock().unwrap_or_else(|e| e.into_inner()) = Some(format!("{msg}{place}"));
        }));
    });
}

fn base_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join("ui")
}

/// Checks the spans of every diagnostic against the text.
fn bad_span(text: &str, analysis: &sdfc::driver::Analysis) -> Option<String> {
    for d in &analysis.diagnostics {
        let spans = d
            .primary
            .iter()
            .chain(&d.secondary)
            .map(|l| l.span)
            .chain(d.fixes.iter().flat_map(|f| f.edits.iter().map(|e| e.span)));
        for s in spans {
            if s.start > s.end
                || s.end > text.len()
                || !text.is_char_boundary(s.start)
                || !text.is_char_boundary(s.end)
            {
                return Some(format!(
                    "{}: span {}..{} outside the text of {} bytes ({})",
                    d.code,
                    s.start,
                    s.end,
                    text.len(),
                    d.message
                ));
            }
        }
    }
    None
}

/// Runs one scene through `check_all` on its own thread (8 MiB of stack, as the main
/// thread has), with a time limit.
fn run(text: &str, limit: Duration) -> Outcome {
    quiet_panics();
    let (tx, rx) = mpsc::channel();
    let owned = text.to_string();
    let handle = std::thread::Builder::new()
        .stack_size(8 << 20)
        .spawn(move || {
            let analysis = sdfc::driver::check_all(&owned, Some(&base_dir()));
            let outcome = if let Some(d) = analysis
                .diagnostics
                .iter()
                .find(|d| d.code == sdfc::codes::E_INTERNAL)
            {
                Outcome::Internal(format!("{}: {}", d.message, d.notes.join(" / ")))
            } else if let Some(why) = bad_span(&owned, &analysis) {
                Outcome::BadSpan(why)
            } else {
                let mut codes: Vec<&'static str> =
                    analysis.diagnostics.iter().map(|d| d.code).collect();
                codes.sort();
                codes.dedup();
                let first_error = analysis.diagnostics.iter().find(|d| d.is_error()).map(|d| {
                    let at = d.span().map(|s| owned[s.range()].to_string());
                    format!("{} {} at {:?}", d.code, d.message, at)
                });
                Outcome::Ok {
                    errors: analysis.has_errors(),
                    codes,
                    first_error,
                }
            };
            let _ = tx.send(outcome);
        })
        .expect("a thread");
    match rx.recv_timeout(limit) {
        Ok(o) => {
            let _ = handle.join();
            o
        }
        Err(mpsc::RecvTimeoutError::Disconnected) => {
            let _ = handle.join();
            let msg = LAST_PANIC
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .take()
                .unwrap_or_else(|| "(no message)".to_string());
            Outcome::Panic(msg)
        }
        // The thread is left running; the process ends with the test.
        Err(mpsc::RecvTimeoutError::Timeout) => Outcome::Hang,
    }
}

/// Structural simplifications of `text`, as (start, end, replacement) edits: a call or
/// parenthesized group replaced by one of its top-level operands or arguments (`name:`
/// stripped), a method call `.f(…)` removed, one argument removed.
fn edits(text: &str) -> Vec<(usize, usize, String)> {
    use sdfc::syntax::lexer::Token;
    let mut d = Vec::new();
    let toks = sdfc::syntax::lexer::lex(text, &mut d).tokens;
    let mut out = Vec::new();
    // Whole items removed.
    let starts: Vec<usize> = toks
        .iter()
        .filter(|(t, _)| t.starts_item())
        .map(|(_, s)| s.start)
        .chain([text.len()])
        .collect();
    for w in starts.windows(2) {
        out.push((w[0], w[1], String::new()));
    }
    for (o, (tok, open)) in toks.iter().enumerate() {
        if !matches!(tok, Token::LParen | Token::LBracket) {
            continue;
        }
        // The matching bracket.
        let mut depth = 0i32;
        let mut close = None;
        for (k, (t, _)) in toks.iter().enumerate().skip(o) {
            match t {
                Token::LParen | Token::LBracket | Token::LBrace => depth += 1,
                Token::RParen | Token::RBracket | Token::RBrace => {
                    depth -= 1;
                    if depth == 0 {
                        close = Some(k);
                        break;
                    }
                }
                _ => {}
            }
        }
        let Some(c) = close else { continue };
        // Top-level pieces between the brackets, split at commas and binary operators.
        let mut pieces = Vec::new();
        let mut depth = 0i32;
        let mut piece_start = o + 1;
        for (k, (t, _)) in toks.iter().enumerate().take(c + 1).skip(o + 1) {
            let split = k == c
                || (depth == 0
                    && matches!(
                        t,
                        Token::Comma
                            | Token::Pipe
                            | Token::Amp
                            | Token::Plus
                            | Token::Minus
                            | Token::Star
                            | Token::Slash
                            | Token::Percent
                    ));
            if split {
                if piece_start < k {
                    pieces.push((piece_start, k));
                }
                piece_start = k + 1;
            }
            match t {
                Token::LParen | Token::LBracket | Token::LBrace => depth += 1,
                Token::RParen | Token::RBracket | Token::RBrace => depth -= 1,
                _ => {}
            }
        }
        let callee = o > 0 && matches!(toks[o - 1].0, Token::Ident(_));
        let group_start = if callee {
            toks[o - 1].1.start
        } else {
            open.start
        };
        let group_end = toks[c].1.end;
        for &(a, b) in &pieces {
            let mut a = a;
            if b - a > 2 && matches!(toks[a].0, Token::Ident(_)) && toks[a + 1].0 == Token::Colon {
                a += 2;
            }
            let piece = text[toks[a].1.start..toks[b - 1].1.end].to_string();
            out.push((group_start, group_end, piece));
            // The argument removed, with its comma.
            let (rs, re) = (toks[a].1.start, toks[b].1.start);
            if toks[b].0 == Token::Comma {
                out.push((rs, toks[b].1.end, String::new()));
            } else if rs < re {
                out.push((rs, re, String::new()));
            }
        }
        // `.f(…)` removed.
        if callee && o >= 2 && toks[o - 2].0 == Token::Dot {
            out.push((toks[o - 2].1.start, group_end, String::new()));
        }
    }
    out
}

/// Greedy delta debugging over lines and tokens, then structural simplifications, to a
/// fixed point: the smallest text found that fails the same way.
fn shrink(text: &str, kind: &str) -> String {
    // Shrinking a hang waits for each try; keep those short.
    let limit = if kind == "hang" {
        Duration::from_secs(3)
    } else {
        HANG
    };
    let fails = |t: &str| {
        let o = run(t, limit);
        o.is_failure() && o.kind() == kind
    };
    let mut best = text.to_string();
    for _round in 0..8 {
        let before = best.clone();
        // Pieces: lines first, then tokens (as byte ranges of the current best).
        for level in 0..2 {
            let mut chunk = 64usize;
            while chunk >= 1 {
                let pieces: Vec<(usize, usize)> = if level == 0 {
                    let mut v = Vec::new();
                    let mut start = 0;
                    for line in best.split_inclusive('\n') {
                        v.push((start, start + line.len()));
                        start += line.len();
                    }
                    v
                } else {
                    let mut d = Vec::new();
                    sdfc::syntax::lexer::lex(&best, &mut d)
                        .tokens
                        .iter()
                        .map(|(_, s)| (s.start, s.end))
                        .collect()
                };
                let mut i = pieces.len();
                let mut changed = false;
                while i > 0 {
                    let lo = i.saturating_sub(chunk);
                    let (a, b) = (pieces[lo].0, pieces[i - 1].1);
                    let candidate = format!("{}{}", &best[..a], &best[b..]);
                    if fails(&candidate) {
                        best = candidate;
                        changed = true;
                    }
                    i = lo;
                }
                if !changed {
                    chunk /= 2;
                }
            }
        }
        // Structural edits, shortest result first, until none applies.
        loop {
            let mut candidates: Vec<String> = edits(&best)
                .into_iter()
                .map(|(a, b, with)| format!("{}{}{}", &best[..a], with, &best[b..]))
                .filter(|c| c.len() < best.len())
                .collect();
            candidates.sort_by_key(String::len);
            match candidates.into_iter().find(|c| fails(c)) {
                Some(c) => best = c,
                None => break,
            }
        }
        if best == before {
            break;
        }
    }
    // Tidy whitespace when that keeps the failure.
    let tidy: String = best
        .lines()
        .map(|l| l.split_whitespace().collect::<Vec<_>>().join(" "))
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join("\n");
    if fails(&tidy) {
        tidy
    } else {
        best
    }
}

struct Report {
    scenes: usize,
    /// Scenes without a mutation, and those of them that checked with no error.
    clean: usize,
    clean_ok: usize,
    mutated: usize,
    mutated_ok: usize,
    /// Scenes without a mutation but with literals far from 1 (not in the pass rate).
    far: usize,
    failures: Vec<String>,
    /// How often each code was reported by a scene without a mutation.
    clean_codes: std::collections::BTreeMap<&'static str, usize>,
    slowest: (Duration, u64),
}

fn run_seeds(seeds: std::ops::Range<u64>, shrink_failures: bool) -> Report {
    let mut r = Report {
        scenes: 0,
        clean: 0,
        clean_ok: 0,
        mutated: 0,
        mutated_ok: 0,
        far: 0,
        failures: Vec::new(),
        clean_codes: Default::default(),
        slowest: (Duration::ZERO, 0),
    };
    let mut kinds_seen = std::collections::HashSet::new();
    for seed in seeds {
        let scene = gen::scene(seed);
        let start = Instant::now();
        let outcome = run(&scene.text, HANG);
        let took = start.elapsed();
        if took > r.slowest.0 {
            r.slowest = (took, seed);
        }
        r.scenes += 1;
        match &outcome {
            Outcome::Ok {
                errors,
                codes,
                first_error,
            } => {
                if scene.mutation.is_some() {
                    r.mutated += 1;
                    r.mutated_ok += usize::from(!errors);
                } else if scene.far {
                    r.far += 1;
                } else {
                    r.clean += 1;
                    r.clean_ok += usize::from(!errors);
                    for c in codes {
                        *r.clean_codes.entry(*c).or_default() += 1;
                    }
                    if let Some(e) = first_error {
                        if std::env::var_os("SDFC_GEN_ERRORS").is_some() {
                            eprintln!("seed {seed}: {e}");
                        }
                    }
                }
            }
            failure => {
                let kind = failure.kind();
                let minimal = if shrink_failures && kinds_seen.insert(kind.clone()) {
                    format!("\nminimal scene:\n{}", shrink(&scene.text, &kind))
                } else {
                    String::new()
                };
                r.failures.push(format!(
                    "seed {seed} ({}): {failure:?}\n{}{minimal}",
                    scene.mutation.unwrap_or("no mutation"),
                    scene.text
                ));
            }
        }
    }
    r
}

fn print(r: &Report, took: Duration) {
    eprintln!(
        "{} scenes in {:.1?} (slowest {:.2?}, seed {}); without a mutation: {}/{} with no error ({:.1}%); mutated: {}/{} with no error; {} with far literals; {} failures",
        r.scenes,
        took,
        r.slowest.0,
        r.slowest.1,
        r.clean_ok,
        r.clean,
        100.0 * r.clean_ok as f64 / r.clean.max(1) as f64,
        r.mutated_ok,
        r.mutated,
        r.far,
        r.failures.len()
    );
    eprintln!("codes in scenes without a mutation: {:?}", r.clean_codes);
    for f in r.failures.iter().take(20) {
        eprintln!("---- {f}");
    }
}

#[test]
fn random_scenes() {
    let start = Instant::now();
    let r = run_seeds(0..500, true);
    print(&r, start.elapsed());
    assert!(
        r.failures.is_empty(),
        "{} of {} random scenes failed; the first:\n{}",
        r.failures.len(),
        r.scenes,
        r.failures[0]
    );
    // The generator's purpose: most scenes check cleanly, so the back end sees them.
    assert!(
        r.clean_ok * 10 >= r.clean * 7,
        "only {}/{} scenes without a mutation checked with no error",
        r.clean_ok,
        r.clean
    );
}

#[test]
#[ignore = "10,000 scenes: run with --release -- --ignored"]
fn ten_thousand_random_scenes() {
    let first: u64 = std::env::var("SDFC_GEN_FIRST")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000);
    let start = Instant::now();
    let r = run_seeds(first..first + 10_000, true);
    print(&r, start.elapsed());
    assert!(
        r.failures.is_empty(),
        "{} of {} random scenes failed",
        r.failures.len(),
        r.scenes
    );
}

/// Prints one scene and its outcome: `SDFC_GEN_SEED=N` (or `SDFC_GEN_FILE=PATH` for a
/// scene of your own, checked as if it were in tests/ui).
#[test]
fn one_seed() {
    let scene = if let Some(path) = std::env::var_os("SDFC_GEN_FILE") {
        gen::Scene {
            seed: 0,
            text: std::fs::read_to_string(path).expect("SDFC_GEN_FILE"),
            mutation: None,
            far: false,
        }
    } else if let Some(seed) = std::env::var("SDFC_GEN_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
    {
        gen::scene(seed)
    } else {
        return;
    };
    eprintln!("{}\nmutation: {:?}", scene.text, scene.mutation);
    let analysis = sdfc::driver::check_all(&scene.text, Some(&base_dir()));
    eprintln!(
        "{}",
        sdfc::diagnostic::render("scene.sdf", &scene.text, &analysis.diagnostics, false)
    );
}
