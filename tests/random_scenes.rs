//! Random well-typed scenes (tests/gen) through the whole check: parse, check, the
//! atlas geometry, lowering, code generation and naga validation
//! (`sdfc::driver::check_all`). Each scene must come back without a panic, without an
//! internal compiler error (`E0900`), with every span inside the text, and in time.
//!
//! A failure names its seed; `SDFC_GEN_SEED=N cargo test --test suite random_scenes::one_seed
//! -- --nocapture` prints that scene and its diagnostics. The 10,000-scene run is
//! `cargo test --release --test suite random_scenes::ten_thousand -- --ignored`.
//!
//! The §5 scenes (`gen::section5`: displacement, shell maps, mirrored and refined
//! atlases, normal maps, textured CSG, atlases on displaced shapes and chains of them)
//! also go through the loop walk when they check; `section5_random_scenes` runs 400 in
//! the suite, and `cargo test --release --test suite random_scenes::section5 -- --ignored
//! --nocapture` runs 1,500 (`SDFC_GEN_FIRST`, `SDFC_GEN_COUNT`) with their times and
//! the peak RSS (`SDFC_GEN_SEED=N SDFC_GEN_S5=1 … one_seed` prints one).

use crate::gen;

use std::path::{Path, PathBuf};
use std::sync::mpsc;
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
        /// With the loop walk too (§5 scenes that checked): whether that module was
        /// accepted (`Some(false)`: a scene error such as E0118); `None` if not tried.
        loop_walk: Option<bool>,
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

fn base_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join("ui")
}

/// Checks the spans of every diagnostic against the text.
fn bad_span(text: &str, analysis: &sdfc::driver::Analysis) -> Option<String> {
    bad_span_of(text, &analysis.diagnostics)
}

fn bad_span_of(text: &str, diagnostics: &[sdfc::diagnostic::Diagnostic]) -> Option<String> {
    for d in diagnostics {
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

/// What `check_all` compiles (the render target, else the first shape), with the loop
/// walk.
fn compile_loop(
    analysis: &sdfc::driver::Analysis,
) -> Result<sdfc::driver::Compiled, sdfc::driver::CompileError> {
    let shape = match (&analysis.program.render, analysis.scene.as_ref()) {
        (None, Some(scene)) => scene.shapes.first().map(|s| s.name.as_str()),
        _ => None,
    };
    let options = sdfc::codegen::Options {
        walk: sdfc::codegen::WalkForm::Loop,
        ..Default::default()
    };
    sdfc::driver::compile_shape(analysis, shape, &options)
}

/// What checking `text` gives (and, with `loop_walk`, compiling it with the loop walk
/// when it checks), on the calling thread.
fn outcome_of(text: &str, loop_walk: bool) -> Outcome {
    let mut analysis = sdfc::driver::check_all(text, Some(&base_dir()));
    if let Some(d) = analysis
        .diagnostics
        .iter()
        .find(|d| d.code == sdfc::codes::E_INTERNAL)
    {
        Outcome::Internal(format!("{}: {}", d.message, d.notes.join(" / ")))
    } else if let Some(why) = bad_span(text, &analysis) {
        Outcome::BadSpan(why)
    } else {
        let mut codes: Vec<&'static str> = analysis.diagnostics.iter().map(|d| d.code).collect();
        codes.sort();
        codes.dedup();
        let first_error = analysis.diagnostics.iter().find(|d| d.is_error()).map(|d| {
            let at = d.span().map(|s| text[s.range()].to_string());
            format!("{} {} at {:?}", d.code, d.message, at)
        });
        let errors = analysis.has_errors();
        let mut loop_ok = None;
        let mut failure = None;
        if loop_walk && analysis.scene.is_some() {
            // A scene that checked has no error but check_all's E0118 (of the
            // unrolled module), which would stop `compile` at once.
            analysis
                .diagnostics
                .retain(|d| d.code != sdfc::codes::E_INLINED_SIZE);
            match compile_loop(&analysis) {
                Ok(_) => loop_ok = Some(true),
                Err(sdfc::driver::CompileError::Internal { diagnostic, .. }) => {
                    failure = Some(Outcome::Internal(format!(
                        "with --walk loop: {}: {}",
                        diagnostic.message,
                        diagnostic.notes.join(" / ")
                    )))
                }
                Err(sdfc::driver::CompileError::Scene(d)) => {
                    loop_ok = Some(false);
                    failure = bad_span_of(text, &d)
                        .map(|why| Outcome::BadSpan(format!("with --walk loop: {why}")));
                }
                Err(sdfc::driver::CompileError::Usage(_)) => loop_ok = Some(false),
            }
        }
        failure.unwrap_or(Outcome::Ok {
            errors,
            codes,
            first_error,
            loop_walk: loop_ok,
        })
    }
}

/// Runs one scene through `check_all` on its own thread (8 MiB of stack, as the main
/// thread has), with a time limit. With `loop_walk`, a scene that checked (its module
/// built, or refused as too large for a driver, E0118) is compiled once more with the
/// loop walk (`--walk loop`, what E0118's help suggests), which must not be an internal
/// error either.
fn run_with(text: &str, limit: Duration, loop_walk: bool) -> Outcome {
    let (tx, rx) = mpsc::channel();
    let owned = text.to_string();
    let handle = std::thread::Builder::new()
        .stack_size(8 << 20)
        .spawn(move || {
            // A panic is a finding: caught quietly, with its message and place.
            let outcome = crate::common::quiet::caught(|| outcome_of(&owned, loop_walk))
                .unwrap_or_else(Outcome::Panic);
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
            let msg = "(the thread ended without an outcome)".to_string();
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
/// fixed point: the smallest text found that fails the same way. Each try runs as
/// [`run_with`] does with `loop_walk`.
fn shrink_with(text: &str, kind: &str, loop_walk: bool) -> String {
    // Shrinking a hang waits for each try; keep those short.
    let limit = if kind == "hang" {
        Duration::from_secs(3)
    } else {
        HANG
    };
    let fails = |t: &str| {
        let o = run_with(t, limit, loop_walk);
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
    /// How often each error code was reported, over all scenes.
    error_codes: std::collections::BTreeMap<&'static str, usize>,
    slowest: (Duration, u64),
    /// Every scene's wall time and seed.
    times: Vec<(Duration, u64)>,
    /// Scenes compiled once more with the loop walk, and those the loop walk built.
    loop_tried: usize,
    loop_ok: usize,
    /// Scenes without a mutation whose only error was E0118 (too large for a driver
    /// with the unrolled walk) and which the loop walk built.
    clean_loop_ok: usize,
}

/// How scenes are made and run.
struct Runner {
    generate: fn(u64) -> gen::Scene,
    /// The time limit of a scene (over it, a hang).
    limit: Duration,
    /// Compile the scenes that check with the loop walk too ([`run_with`]).
    loop_walk: bool,
    /// Shrink the first failure of each kind.
    shrink: bool,
}

const GENERIC: Runner = Runner {
    generate: gen::scene,
    limit: HANG,
    loop_walk: false,
    shrink: true,
};

fn run_seeds(seeds: std::ops::Range<u64>, shrink_failures: bool) -> Report {
    run_scenes(
        seeds,
        &Runner {
            shrink: shrink_failures,
            ..GENERIC
        },
    )
}

fn run_scenes(seeds: std::ops::Range<u64>, runner: &Runner) -> Report {
    let mut r = Report {
        scenes: 0,
        clean: 0,
        clean_ok: 0,
        mutated: 0,
        mutated_ok: 0,
        far: 0,
        failures: Vec::new(),
        clean_codes: Default::default(),
        error_codes: Default::default(),
        slowest: (Duration::ZERO, 0),
        times: Vec::new(),
        loop_tried: 0,
        loop_ok: 0,
        clean_loop_ok: 0,
    };
    let mut kinds_seen = std::collections::HashSet::new();
    for seed in seeds {
        let scene = (runner.generate)(seed);
        let start = Instant::now();
        let outcome = run_with(&scene.text, runner.limit, runner.loop_walk);
        let took = start.elapsed();
        if took > r.slowest.0 {
            r.slowest = (took, seed);
        }
        r.times.push((took, seed));
        r.scenes += 1;
        match &outcome {
            Outcome::Ok {
                errors,
                codes,
                first_error,
                loop_walk,
            } => {
                for c in codes.iter().filter(|c| c.starts_with('E')) {
                    *r.error_codes.entry(*c).or_default() += 1;
                }
                if let Some(ok) = loop_walk {
                    r.loop_tried += 1;
                    r.loop_ok += usize::from(*ok);
                }
                if scene.mutation.is_some() {
                    r.mutated += 1;
                    r.mutated_ok += usize::from(!errors);
                } else if scene.far {
                    r.far += 1;
                } else {
                    r.clean += 1;
                    r.clean_ok += usize::from(!errors);
                    let only_e0118 = codes
                        .iter()
                        .filter(|c| c.starts_with('E'))
                        .all(|c| *c == "E0118");
                    if *errors && only_e0118 && *loop_walk == Some(true) {
                        r.clean_loop_ok += 1;
                    }
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
                let minimal = if runner.shrink && kinds_seen.insert(kind.clone()) {
                    format!(
                        "\nminimal scene:\n{}",
                        shrink_with(&scene.text, &kind, runner.loop_walk)
                    )
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
    eprintln!("error codes over all scenes: {:?}", r.error_codes);
    if r.loop_tried > 0 {
        eprintln!(
            "with the loop walk too: {}/{} built; without a mutation, {} more scenes ({}/{}, {:.1}%, in all) built with the loop walk where the unrolled one was too large (E0118)",
            r.loop_ok,
            r.loop_tried,
            r.clean_loop_ok,
            r.clean_ok + r.clean_loop_ok,
            r.clean,
            100.0 * (r.clean_ok + r.clean_loop_ok) as f64 / r.clean.max(1) as f64
        );
    }
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

// ------------------------------------------------------------------ §5 scenes

/// The §5 scenes (`gen::section5::section5_scene`): checked as the others, and each
/// that checks is compiled once more with the loop walk.
const SECTION5: Runner = Runner {
    generate: gen::section5::section5_scene,
    limit: HANG,
    loop_walk: true,
    shrink: true,
};

/// The share of §5 scenes without a mutation (nor far literals) that must check with
/// no error, in percent (seeds 0..400: 160/291, 55.0 %). The rest are mostly the
/// compiler's refusals of nested walks (E0118 about 26 %, E0119 about 11 %), merges
/// that do not reach and the generator's deliberate E0206/E0207 heights.
const SECTION5_CLEAN_SHARE: usize = 50;
/// The share, in percent, that check with no error or whose only error, E0118, the
/// loop walk avoids (seeds 0..400: 174/291, 59.8 %).
const SECTION5_BUILT_SHARE: usize = 55;

#[test]
fn section5_random_scenes() {
    let start = Instant::now();
    let r = run_scenes(0..SECTION5_SCENES, &SECTION5);
    print(&r, start.elapsed());
    assert!(
        r.failures.is_empty(),
        "{} of {} §5 scenes failed; the first:\n{}",
        r.failures.len(),
        r.scenes,
        r.failures[0]
    );
    assert!(
        r.clean_ok * 100 >= r.clean * SECTION5_CLEAN_SHARE,
        "only {}/{} §5 scenes without a mutation checked with no error",
        r.clean_ok,
        r.clean
    );
    assert!(
        (r.clean_ok + r.clean_loop_ok) * 100 >= r.clean * SECTION5_BUILT_SHARE,
        "only {}/{} §5 scenes without a mutation built (unrolled, or with the loop walk)",
        r.clean_ok + r.clean_loop_ok,
        r.clean
    );
}

/// Every §5 construct the generator is meant to write appears in the suite's scenes.
#[test]
fn section5_generator_covers_every_construct() {
    let scenes: Vec<String> = (0..SECTION5_SCENES)
        .map(|seed| gen::section5::section5_scene(seed).text)
        .collect();
    let any = |f: &dyn Fn(&str) -> bool| scenes.iter().any(|t| f(t));
    let lines = |f: &dyn Fn(&str) -> bool| any(&|t: &str| t.lines().any(f));
    let wanted: &[(&str, &dyn Fn(&str) -> bool)] = &[
        ("a constant height", &|l| l.contains(".displace(0.5")),
        ("a texture height at an atlas's uv", &|l| {
            l.contains("displace(") && l.contains(".sample(") && l.contains(".uv")
        }),
        ("math of an atlas's uv", &|l| {
            l.contains("displace(sin(atlas")
        }),
        ("an atlas's distance", &|l| {
            l.contains("displace(") && l.contains(".distance")
        }),
        ("displace as a function", &|l| l.contains("= displace(")),
        ("a shell map at an atlas's uv", &|l| {
            l.contains(".shell_map(") && l.contains(".uv")
        }),
        ("a shell map at a constant uv", &|l| {
            l.contains(", [0.5, 0.5]")
        }),
        ("a shell map without its base", &|l| {
            l.contains("base: false")
        }),
        ("displace then shell_map", &|l| {
            l.find(".displace(")
                .is_some_and(|i| l[i..].contains(".shell_map("))
        }),
        ("shell_map then displace", &|l| {
            l.find(".shell_map(")
                .is_some_and(|i| l[i..].contains(".displace("))
        }),
        ("a displaced plane", &|l| l.contains("plane().displace(")),
        ("a shell-mapped lattice", &|l| {
            l.contains(".repeat(2).shell_map(")
        }),
        ("a scale of 1e30", &|l| l.contains("scale: 1e30")),
        ("a scale of 1.8e38", &|l| l.contains("scale: 1.8e38")),
        ("a mirrored atlas", &|l| l.contains("mirror = [")),
        ("refine = 0", &|l| l.contains("refine = 0")),
        ("refine = 1", &|l| l.contains("refine = 1")),
        ("refine = 2", &|l| l.contains("refine = 2")),
        ("a merge of three seeds", &|l| {
            l.trim_start().starts_with("merge ") && l.split_whitespace().count() >= 4
        }),
        ("an atlas on a displaced shape", &|l| {
            l.starts_with("atlas ") && l.contains(" on d")
        }),
        ("an atlas on a union", &|l| {
            l.starts_with("atlas ") && l.contains(" | ")
        }),
        ("a normal map", &|l| {
            l.contains("normal = ") && l.contains("sample_normal(")
        }),
        ("a DirectX normal map", &|l| {
            l.contains("convention: \"dx\"")
        }),
        ("a painted smooth union", &|l| {
            l.starts_with("render smooth_union(") && l.contains(".paint(")
        }),
        ("a painted intersection", &|l| {
            l.contains(") & ") && l.contains(".paint(")
        }),
        ("a painted difference", &|l| {
            l.contains(") - ") && l.contains(".paint(")
        }),
        ("a smooth difference", &|l| l.contains("smooth_difference(")),
        ("a twisted operand", &|l| l.contains(".twist(axis:")),
        ("a mirrored operand", &|l| l.contains(".mirror(")),
        ("paint before displace", &|l| {
            l.contains(".paint(m") && l.contains(").displace(")
        }),
        ("a tile with an atlas", &|l| l.contains(".shell_map(d")),
    ];
    let missing: Vec<&str> = wanted
        .iter()
        .filter(|(_, f)| !lines(*f))
        .map(|(name, _)| *name)
        .collect();
    assert!(missing.is_empty(), "never generated: {missing:?}");
}

/// The number of §5 scenes of the suite's run.
const SECTION5_SCENES: u64 = 400;

/// The process's peak resident set, in bytes: `VmHWM` of /proc/self/status, else
/// getrusage's `ru_maxrss`. The latter survives execve, so under `cargo test` it is at
/// least cargo's own peak (86 MiB here) however little the tests use.
fn peak_rss() -> Option<u64> {
    let hwm = std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            let line = s.lines().find(|l| l.starts_with("VmHWM:"))?.to_string();
            line.split_whitespace().nth(1)?.parse::<u64>().ok()
        })
        .map(|kib| kib * 1024);
    hwm.or_else(max_rss)
}

#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn max_rss() -> Option<u64> {
    // SAFETY: getrusage writes the struct it is given, which is plain data.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let rc = unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) };
    // Linux gives ru_maxrss in KiB.
    (rc == 0).then(|| usage.ru_maxrss as u64 * 1024)
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn max_rss() -> Option<u64> {
    None
}

#[test]
#[ignore = "1,500 §5 scenes: run with --release -- --ignored"]
fn section5_random_scenes_long() {
    // The process's peak memory is this test's alone.
    if !crate::common::in_own_process("random_scenes::section5_random_scenes_long") {
        return;
    }
    // A scene over HANG (10 s, the suite's limit) is a failure; it runs until SLOW, so
    // that its time is measured, and beyond that it is reported as a hang (shrunk).
    const SLOW: Duration = Duration::from_secs(20);
    const MAX_RSS: u64 = 1 << 30;
    let first: u64 = std::env::var("SDFC_GEN_FIRST")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(5_000_000);
    let count: u64 = std::env::var("SDFC_GEN_COUNT")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_500);
    let start = Instant::now();
    let mut r = run_scenes(
        first..first + count,
        &Runner {
            limit: SLOW,
            ..SECTION5
        },
    );
    let mut times = r.times.clone();
    times.sort_by(|a, b| b.cmp(a));
    for &(t, seed) in times.iter().filter(|(t, _)| *t > HANG) {
        r.failures.push(format!(
            "seed {seed}: took {t:.1?} (over {HANG:?})\n{}",
            gen::section5::section5_scene(seed).text
        ));
    }
    print(&r, start.elapsed());
    let slowest: Vec<String> = times
        .iter()
        .take(5)
        .map(|(t, seed)| format!("seed {seed} {t:.2?}"))
        .collect();
    eprintln!("slowest: {}", slowest.join(", "));
    let over = |s: u64| {
        times
            .iter()
            .filter(|(t, _)| *t > Duration::from_secs(s))
            .count()
    };
    eprintln!(
        "scenes over 1 s: {}, over 5 s: {}, over 10 s: {}",
        over(1),
        over(5),
        over(10)
    );
    let rss = peak_rss();
    match rss {
        Some(b) => eprintln!("peak RSS: {:.1} MiB", b as f64 / (1 << 20) as f64),
        None => eprintln!("peak RSS: unknown on this platform"),
    }
    assert!(
        r.failures.is_empty(),
        "{} of {} §5 scenes failed; the first:\n{}",
        r.failures.len(),
        r.scenes,
        r.failures[0]
    );
    assert!(
        rss.is_none_or(|b| b <= MAX_RSS),
        "peak RSS {rss:?} bytes, over {MAX_RSS}"
    );
}

/// Prints one scene and its outcome: `SDFC_GEN_SEED=N` (or `SDFC_GEN_FILE=PATH` for a
/// scene of your own, checked as if it were in tests/ui); with `SDFC_GEN_S5=1`, the §5
/// scene of the seed, and the outcome of [`run_with`] with the loop walk.
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
        if std::env::var_os("SDFC_GEN_S5").is_some() {
            gen::section5::section5_scene(seed)
        } else {
            gen::scene(seed)
        }
    } else {
        return;
    };
    eprintln!("{}\nmutation: {:?}", scene.text, scene.mutation);
    let analysis = sdfc::driver::check_all(&scene.text, Some(&base_dir()));
    eprintln!(
        "{}",
        sdfc::diagnostic::render("scene.sdf", &scene.text, &analysis.diagnostics, false)
    );
    if std::env::var_os("SDFC_GEN_S5").is_some() {
        let mut analysis = analysis;
        analysis
            .diagnostics
            .retain(|d| d.code != sdfc::codes::E_INLINED_SIZE);
        if analysis.scene.is_some() {
            match compile_loop(&analysis) {
                Ok(_) => eprintln!("the loop walk builds it"),
                Err(sdfc::driver::CompileError::Scene(d)) => eprintln!(
                    "with the loop walk:\n{}",
                    sdfc::diagnostic::render("scene.sdf", &scene.text, &d, false)
                ),
                Err(sdfc::driver::CompileError::Internal { diagnostic, .. }) => eprintln!(
                    "with the loop walk:\n{}",
                    sdfc::diagnostic::render("scene.sdf", &scene.text, &[*diagnostic], false)
                ),
                Err(e) => eprintln!("with the loop walk: {e:?}"),
            }
        }
        let start = Instant::now();
        let o = run_with(&scene.text, HANG, true);
        eprintln!("with the loop walk too: {o:?} in {:.2?}", start.elapsed());
    }
}
