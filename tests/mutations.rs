//! Mutations of the examples (`examples/*.sdf`) through the whole check, the formatter
//! and the seed placement of `sdfc seeds --write`: the random scene generator's
//! token-level mutations (`tests/gen`, `gen::mutate`) and byte-level edits (cuts,
//! insertions, duplications, moves, flipped bits, spliced lines, extreme numbers,
//! deep nesting), one to three stacked on one example. Each mutated text must:
//!
//! - go through `sdfc::driver::check_all` without a panic, without an internal
//!   compiler error (E0900), with every span inside the text;
//! - format idempotently, keeping its tokens (`fuzz/fuzz_targets/targets.rs`, `format`);
//! - when it checks without errors (an atlas without seeds aside, as `sdfc seeds`
//!   allows) and has an atlas: place that atlas's seeds (`place_edit` on a 12-cell
//!   grid) without a panic, and, applied, give a text that parses and keeps every byte
//!   outside the replaced `seed` and `merge` statements (`targets::assert_seeds_edit`);
//! - all of it within 20 s; the process's peak resident memory stays under 1 GB.
//!
//! Some cases (one in 10 in the suite, one in 4 in the long run) also go through the
//! binary: `sdfc fmt` and `sdfc seeds --write` on the text as a file, which must not
//! crash or hang, and must write a formatted or checked text or leave the file as it
//! was. Edits that hit a known bug are left out unless `SDFC_MUT_ALL=1`
//! (`mutate::KNOWN_BUGS`).
//!
//! Every case comes from one `u64` seed: `SDFC_MUT_SEED=N cargo test --release --test
//! suite mutations::one_mutation -- --nocapture` prints case N's text and what it gave. The
//! 10,000-mutation run: `cargo test --release --test suite mutations:: -- --ignored
//! --nocapture` (`SDFC_MUT_COUNT` sets the count); it shrinks each distinct failure.

use crate::common::quiet::caught;
#[allow(unused)]
use crate::gen;
use crate::mutate;

#[path = "../fuzz/fuzz_targets/targets.rs"]
mod targets;

use gen::Rng;
use mutate::{case, examples, examples_dir, lex, Case};
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// A case that takes longer than this is a failure (a hang).
const HANG: Duration = Duration::from_secs(20);

/// The most resident memory the process may have had at its peak.
const MAX_RSS_KB: u64 = 1 << 20;

/// The seeds of the ignored run start here (the in-suite run takes 0, 1, 2, …).
const IGNORED_BASE: u64 = 1_000_000;

// ---------------------------------------------------------------- the properties

/// What one case gave.
#[derive(Debug, Clone, Default)]
struct Stats {
    /// The check found errors.
    errors: bool,
    /// Atlases whose seeds were placed (anew or kept) and the edit checked.
    placed: usize,
    /// Placements refused with an `Err` (not a failure).
    refused: usize,
    /// Edited texts that have errors after placing anew (what `sdfc seeds --write`
    /// refuses to write): (codes, the first error's message).
    placed_errors: Vec<(String, String)>,
    /// The atlas placed (what `sdfc seeds --write --atlas` gets in the binary's turn).
    atlas: Option<String>,
}

#[derive(Debug, Clone)]
enum Outcome {
    Ok(Stats),
    /// Where (check_all, E0900, span, format, seeds, hang) and what.
    Failed(&'static str, String),
}

/// The properties of one text (see the module docs), on the calling thread.
fn properties(text: &str, base: &Path, rng: &mut Rng) -> Outcome {
    let analysis = match caught(|| sdfc::driver::check_all(text, Some(base))) {
        Ok(a) => a,
        Err(m) => return Outcome::Failed("check_all panic", m),
    };
    if let Some(d) = analysis
        .diagnostics
        .iter()
        .find(|d| d.code == sdfc::codes::E_INTERNAL)
    {
        return Outcome::Failed("E0900", format!("{} / {}", d.message, d.notes.join(" / ")));
    }
    if let Err(m) = caught(|| targets::assert_spans(text, &analysis.diagnostics)) {
        return Outcome::Failed("span", m);
    }
    if let Err(m) = caught(|| targets::format(text.as_bytes())) {
        return Outcome::Failed("format", m);
    }
    let mut stats = Stats {
        errors: analysis.has_errors(),
        ..Stats::default()
    };
    let blocking = analysis
        .diagnostics
        .iter()
        .any(|d| d.is_error() && d.code != sdfc::codes::E_NO_SEEDS);
    if blocking || analysis.program.atlases.is_empty() {
        return Outcome::Ok(stats);
    }
    // One atlas (the examples have one or two), anew; a quarter of the time also kept.
    let atlases = &analysis.program.atlases;
    let name = atlases[rng.below(atlases.len())].name.clone();
    stats.atlas = Some(name.clone());
    let keep_too = rng.chance(0.25);
    let doc = sdfc::ide::Document {
        text: text.to_string(),
        analysis,
    };
    for keep in [false, true] {
        if keep && !keep_too {
            continue;
        }
        let placed = caught(|| targets::place_seeds(&doc, &name, keep, targets::SEEDS_GRID));
        let output = match placed {
            Err(m) => return Outcome::Failed("seeds", m),
            Ok(None) => {
                stats.refused += 1;
                continue;
            }
            Ok(Some(o)) => o,
        };
        stats.placed += 1;
        if keep {
            continue;
        }
        // What `sdfc seeds --write` does next: format, and check before writing.
        let after = caught(|| {
            let formatted = sdfc::ide::format::format(&output).unwrap_or(output.clone());
            sdfc::driver::check(&formatted, Some(base))
        });
        match after {
            Err(m) => return Outcome::Failed("seeds check", m),
            Ok(a) => {
                // (Another atlas still without seeds is not this placement's.)
                let other = |d: &sdfc::Diagnostic| {
                    d.code == sdfc::codes::E_NO_SEEDS && !d.message.contains(&format!("`{name}`"))
                };
                let errors: Vec<&sdfc::Diagnostic> = a
                    .diagnostics
                    .iter()
                    .filter(|d| d.is_error() && !other(d))
                    .collect();
                if !errors.is_empty() {
                    let codes: Vec<&str> = errors.iter().map(|d| d.code).collect();
                    stats
                        .placed_errors
                        .push((codes.join(","), errors[0].message.clone()));
                }
            }
        }
    }
    Outcome::Ok(stats)
}

/// Runs the properties of `text` on a thread of its own (8 MiB of stack, as the main
/// thread has), with the [`HANG`] limit; the case's time with it. A thread that hangs
/// is left running (the process ends with the test).
fn run(text: &str, seed: u64, limit: Duration) -> (Outcome, Duration) {
    let (tx, rx) = mpsc::channel();
    let owned = text.to_string();
    let started = Instant::now();
    let handle = std::thread::Builder::new()
        .stack_size(8 << 20)
        .spawn(move || {
            let mut rng = Rng::new(seed ^ 0x5eed);
            let o = properties(&owned, &examples_dir(), &mut rng);
            let _ = tx.send(o);
        })
        .expect("a thread");
    match rx.recv_timeout(limit) {
        Ok(o) => {
            let took = started.elapsed();
            let _ = handle.join();
            if took > limit {
                return (
                    Outcome::Failed("hang", format!("took {:.1} s", took.as_secs_f64())),
                    took,
                );
            }
            (o, took)
        }
        Err(_) => (
            Outcome::Failed("hang", format!("over {} s", limit.as_secs())),
            started.elapsed(),
        ),
    }
}

/// What must stay the same while a failing text is shrunk: the stage, and the first
/// line of the message without numbers.
fn failure_key(stage: &str, message: &str) -> String {
    let first = message.lines().next().unwrap_or("");
    format!(
        "{stage}: {}",
        first.replace(|c: char| c.is_ascii_digit(), "")
    )
}

/// Greedy delta debugging over lines, then tokens, then characters, while the failure
/// stays the same; at most `budget` of time.
fn shrink(text: &str, seed: u64, key: &str, budget: Duration) -> String {
    let started = Instant::now();
    let limit = if key.starts_with("hang") {
        HANG
    } else {
        Duration::from_secs(10)
    };
    let fails = |t: &str| match run(t, seed, limit).0 {
        Outcome::Failed(stage, m) => failure_key(stage, &m) == key,
        Outcome::Ok(_) => false,
    };
    let mut best = text.to_string();
    loop {
        let before = best.clone();
        for level in 0..3 {
            let mut chunk = 32usize;
            while chunk >= 1 {
                if started.elapsed() > budget {
                    return best;
                }
                let pieces: Vec<(usize, usize)> = match level {
                    0 => {
                        let mut v = Vec::new();
                        let mut start = 0;
                        for line in best.split_inclusive('\n') {
                            v.push((start, start + line.len()));
                            start += line.len();
                        }
                        v
                    }
                    1 => lex(&best).iter().map(|(_, s)| (s.start, s.end)).collect(),
                    _ => best
                        .char_indices()
                        .map(|(i, c)| (i, i + c.len_utf8()))
                        .collect(),
                };
                let mut i = pieces.len();
                let mut changed = false;
                while i > 0 {
                    if started.elapsed() > budget {
                        return best;
                    }
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
        if best == before {
            return best;
        }
    }
}

/// The process's peak resident memory (VmHWM), in KiB.
fn peak_rss_kb() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap_or(0)
}

/// Runs the `sdfc` binary in `dir` with a [`HANG`] limit: its exit code (`None`
/// when a signal ended it) and standard error; `Err` when it ran out of time.
fn sdfc_in(dir: &Path, args: &[&str]) -> Result<(Option<i32>, String), String> {
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_sdfc"))
        .args(args)
        .current_dir(dir)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = std::io::Read::read_to_string(&mut err, &mut s);
        s
    });
    let started = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if started.elapsed() > HANG {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!(
                "sdfc {} ran over {} s",
                args.join(" "),
                HANG.as_secs()
            ));
        }
        std::thread::sleep(Duration::from_millis(2));
    };
    Ok((status.code(), reader.join().unwrap_or_default()))
}

/// `sdfc fmt` and `sdfc seeds --write` (of `atlas`, on a 12-cell grid) on `text` as a
/// file of `dir` (which has the examples' textures): never a crash, an internal
/// compiler error or a hang; `fmt` writes the formatter's text or, on syntax errors,
/// nothing; `seeds --write` writes a text that checks without errors or leaves the
/// file as it was. Returns how many runs were made.
fn cli(dir: &Path, text: &str, atlas: Option<&str>) -> Result<usize, (&'static str, String)> {
    let file = dir.join("scene.sdf");
    std::fs::write(&file, text).unwrap();
    let (code, err) = sdfc_in(dir, &["fmt", "scene.sdf"]).map_err(|e| ("hang", e))?;
    let now = std::fs::read_to_string(&file).unwrap_or_default();
    match (code, sdfc::ide::format::format(text)) {
        (Some(0), Ok(formatted)) if now == formatted => {}
        (Some(1), Err(_)) if now == text => {}
        (code, formatted) => {
            return Err((
                "fmt binary",
                format!(
                    "exit {code:?}, formatter {}, file {}: {}",
                    if formatted.is_ok() { "ok" } else { "refused" },
                    if now == text { "unchanged" } else { "changed" },
                    err.trim()
                ),
            ))
        }
    }
    let Some(atlas) = atlas else {
        return Ok(1);
    };
    std::fs::write(&file, text).unwrap();
    let args = [
        "seeds",
        "scene.sdf",
        "--write",
        "--grid",
        "12",
        "--atlas",
        atlas,
    ];
    let (code, err) = sdfc_in(dir, &args).map_err(|e| ("hang", e))?;
    let now = std::fs::read_to_string(&file).unwrap_or_default();
    match code {
        Some(0) => {
            // Another atlas still without seeds (E0115) is not this placement's: `seeds`
            // places one atlas's, as the in-process property above allows.
            let a = sdfc::driver::check(&now, Some(dir));
            let errors: Vec<&sdfc::Diagnostic> = a
                .diagnostics
                .iter()
                .filter(|d| {
                    d.is_error()
                        && !(d.code == sdfc::codes::E_NO_SEEDS
                            && !d.message.contains(&format!("`{atlas}`")))
                })
                .collect();
            if !errors.is_empty() {
                return Err((
                    "seeds binary",
                    format!("the written file has errors: {errors:?}"),
                ));
            }
        }
        Some(1 | 2) if now == text => {}
        code => {
            return Err((
                "seeds binary",
                format!(
                    "exit {code:?}, file {}: {}",
                    if now == text { "unchanged" } else { "changed" },
                    err.trim()
                ),
            ))
        }
    }
    Ok(2)
}

/// A failure found, with its case.
struct Found {
    case: Case,
    stage: &'static str,
    message: String,
    took: Duration,
}

/// Runs cases `base .. base + count` (every `cli_every`-th also through the binary);
/// prints the figures and returns the failures.
fn sweep(base: u64, count: u64, cli_every: u64, shrink_budget: Option<Duration>) -> Vec<Found> {
    let examples = examples();
    // A folder for the binary's files, with the examples' textures.
    let dir = tempfile::tempdir().unwrap();
    let textures = dir.path().join("textures");
    std::fs::create_dir(&textures).unwrap();
    for e in std::fs::read_dir(examples_dir().join("textures")).unwrap() {
        let p = e.unwrap().path();
        std::fs::copy(&p, textures.join(p.file_name().unwrap())).unwrap();
    }
    let mut cli_runs = 0;
    let started = Instant::now();
    let mut found: Vec<Found> = Vec::new();
    let mut kinds: BTreeMap<&str, usize> = BTreeMap::new();
    let (mut clean, mut with_errors, mut placed, mut refused, mut cases_placed) = (0, 0, 0, 0, 0);
    let mut placed_errors: BTreeMap<String, (usize, u64, String)> = BTreeMap::new();
    let mut slowest: (Duration, u64, String) = (Duration::ZERO, 0, String::new());
    let mut times: Vec<Duration> = Vec::new();
    for seed in base..base + count {
        let c = case(seed, &examples);
        for k in &c.kinds {
            *kinds.entry(k).or_default() += 1;
        }
        let (outcome, took) = run(&c.text, seed, HANG);
        times.push(took);
        if took > slowest.0 {
            slowest = (took, seed, c.example.clone());
        }
        let outcome = match outcome {
            // One case in `cli_every`, drawn apart from the example's turn.
            Outcome::Ok(s) if Rng::new(seed ^ 0xc11).below(cli_every as usize) == 0 => {
                match cli(dir.path(), &c.text, s.atlas.as_deref()) {
                    Ok(n) => {
                        cli_runs += n;
                        Outcome::Ok(s)
                    }
                    Err((stage, m)) => Outcome::Failed(stage, m),
                }
            }
            o => o,
        };
        match outcome {
            Outcome::Ok(s) => {
                if s.errors {
                    with_errors += 1;
                } else {
                    clean += 1;
                }
                placed += s.placed;
                refused += s.refused;
                if s.placed > 0 {
                    cases_placed += 1;
                }
                for (codes, message) in s.placed_errors {
                    placed_errors.entry(codes).or_insert((0, seed, message)).0 += 1;
                }
            }
            Outcome::Failed(stage, message) => {
                eprintln!(
                    "FAILED case {seed} ({}, {:?}): {stage}: {}",
                    c.example,
                    c.kinds,
                    message.lines().next().unwrap_or("")
                );
                found.push(Found {
                    case: c,
                    stage,
                    message,
                    took,
                });
            }
        }
    }
    times.sort();
    let total = started.elapsed();
    let rss = peak_rss_kb();
    eprintln!(
        "mutations: {count} cases (seeds {base}..{}) in {:.1} s: {clean} check without errors, {with_errors} with errors, {} failures",
        base + count,
        total.as_secs_f64(),
        found.len()
    );
    eprintln!("mutation kinds: {kinds:?}");
    eprintln!("binary runs (sdfc fmt, sdfc seeds --write): {cli_runs}");
    eprintln!(
        "seeds placed: {placed} edits checked in {cases_placed} cases ({refused} placements refused with an error)"
    );
    for (codes, (n, seed, message)) in &placed_errors {
        eprintln!(
            "  placed seeds then check with errors [{codes}] x{n} (e.g. case {seed}: {message})"
        );
    }
    if !times.is_empty() {
        let q = |p: f64| times[((times.len() - 1) as f64 * p) as usize].as_secs_f64() * 1e3;
        eprintln!(
            "time per case: median {:.1} ms, p99 {:.1} ms; slowest {:.2} s (case {}, {})",
            q(0.5),
            q(0.99),
            slowest.0.as_secs_f64(),
            slowest.1,
            slowest.2
        );
    }
    eprintln!("peak RSS (VmHWM): {:.1} MiB", rss as f64 / 1024.0);
    if rss > MAX_RSS_KB {
        found.push(Found {
            case: Case {
                seed: base,
                example: String::new(),
                kinds: Vec::new(),
                text: String::new(),
            },
            stage: "memory",
            message: format!("peak RSS {rss} kB is over 1 GB"),
            took: total,
        });
    }
    // Each distinct failure once, shrunk.
    if let Some(budget) = shrink_budget {
        let mut keys = std::collections::BTreeSet::new();
        for f in &found {
            let key = failure_key(f.stage, &f.message);
            if f.stage == "memory" || !keys.insert(key.clone()) {
                continue;
            }
            let small = shrink(&f.case.text, f.case.seed, &key, budget);
            eprintln!(
                "--- failure {key}\n    case {} ({}, {:?}, {:.2} s)\n    message: {}\n--- reproducer ({} bytes)\n{small}\n---",
                f.case.seed,
                f.case.example,
                f.case.kinds,
                f.took.as_secs_f64(),
                f.message.lines().take(3).collect::<Vec<_>>().join(" / "),
                small.len()
            );
        }
    }
    found
}

fn assert_none(found: &[Found]) {
    if found.is_empty() {
        return;
    }
    let list: Vec<String> = found
        .iter()
        .map(|f| {
            format!(
                "case {} ({}, {:?}): {}: {}\n{}",
                f.case.seed,
                f.case.example,
                f.case.kinds,
                f.stage,
                f.message.lines().take(4).collect::<Vec<_>>().join(" / "),
                f.case.text
            )
        })
        .collect();
    panic!(
        "{} failures (SDFC_MUT_SEED=N … one_mutation reproduces one):\n{}",
        found.len(),
        list.join("\n\n")
    );
}

/// The in-suite run: 500 cases (about 20 s in release on two busy cores; seed
/// placement with its stretch target costs about three times what coverage alone did,
/// so the in-suite count went from 1,500 to 500 to keep CI under its 15 minutes).
#[test]
fn mutated_examples_check_format_and_place_seeds() {
    // The process's peak memory is this test's alone.
    if !crate::common::in_own_process("mutations::mutated_examples_check_format_and_place_seeds") {
        return;
    }
    let found = sweep(0, 500, 10, None);
    assert_none(&found);
}

/// The long run: 10,000 cases (`SDFC_MUT_COUNT`), each distinct failure shrunk to a
/// reproducer.
#[test]
#[ignore]
fn many_mutated_examples_check_format_and_place_seeds() {
    if !crate::common::in_own_process(
        "mutations::many_mutated_examples_check_format_and_place_seeds",
    ) {
        return;
    }
    let count = std::env::var("SDFC_MUT_COUNT")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(10_000);
    let found = sweep(IGNORED_BASE, count, 4, Some(Duration::from_secs(120)));
    assert_none(&found);
}

/// `SDFC_MUT_SEED=N`: case N's text and what it gave (nothing without the variable).
#[test]
fn one_mutation() {
    let Some(seed) = std::env::var("SDFC_MUT_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
    else {
        return;
    };
    let c = case(seed, &examples());
    println!(
        "case {seed}: {} with {:?}\n---\n{}\n---",
        c.example, c.kinds, c.text
    );
    let (outcome, took) = run(&c.text, seed, HANG);
    println!("{outcome:?} in {:.3} s", took.as_secs_f64());
    let a = sdfc::driver::check_all(&c.text, Some(&examples_dir()));
    print!(
        "{}",
        sdfc::diagnostic::render(&c.example, &c.text, &a.diagnostics, false)
    );
}
