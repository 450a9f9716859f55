//! The suite's own helpers (tests/common): what the other files rely on to share one
//! process.

use crate::common::quiet;

/// A quiet thread keeps its panic's message and place; a thread that did not ask keeps
/// nothing (its panic goes to the hook that was there before, which prints it).
#[test]
fn quiet_panics_stay_on_the_threads_that_ask() {
    let quiet_one = std::thread::spawn(|| quiet::caught(|| panic!("a finding")))
        .join()
        .unwrap();
    let message = quiet_one.expect_err("the panic is caught");
    assert!(message.starts_with("a finding at "), "{message}");
    assert!(message.contains("harness.rs"), "{message}");

    let loud_one = std::thread::spawn(|| {
        let caught = std::panic::catch_unwind(|| panic!("an assertion elsewhere"));
        (caught.is_err(), quiet::take())
    })
    .join()
    .unwrap();
    assert!(loud_one.0);
    assert_eq!(loud_one.1, None, "a thread that did not ask kept its panic");

    // Nothing is left behind on a quiet thread once taken, and no panic gives Ok.
    let clean = std::thread::spawn(|| (quiet::caught(|| 7), quiet::take()))
        .join()
        .unwrap();
    assert_eq!(clean, (Ok(7), None));
}

/// The test that runs alone: in the suite's process it runs the binary again with only
/// itself, where it finds itself alone.
#[test]
fn a_test_can_run_in_a_process_of_its_own() {
    if !crate::common::in_own_process("harness::a_test_can_run_in_a_process_of_its_own") {
        return;
    }
    assert_eq!(
        std::env::var("SDFC_TEST_ALONE").as_deref(),
        Ok("harness::a_test_can_run_in_a_process_of_its_own")
    );
}

/// A name that is no test's fails, instead of passing with nothing run.
#[test]
#[should_panic(expected = "is not the name of one test")]
fn a_process_of_its_own_needs_a_real_name() {
    crate::common::in_own_process("harness::no_such_test");
}

/// Every file of tests/ is a module of the suite: with `autotests = false`, a file left
/// out of tests/suite.rs would never run, and nothing would say so.
#[test]
fn every_file_of_tests_is_in_the_suite() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    let suite = std::fs::read_to_string(root.join("suite.rs")).unwrap();
    let mut missing = Vec::new();
    for e in std::fs::read_dir(&root).unwrap() {
        let path = e.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if name == "suite.rs" || !name.ends_with(".rs") {
            continue;
        }
        let stem = name.trim_end_matches(".rs");
        if !suite.contains(&format!("#[path = \"{name}\"]\nmod {stem};\n")) {
            missing.push(name);
        }
    }
    assert!(missing.is_empty(), "not in tests/suite.rs: {missing:?}");
}
