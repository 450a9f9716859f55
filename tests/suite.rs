//! The integration tests, built as one test binary.
//!
//! Each `tests/NAME.rs` is a module of this crate (run one with
//! `cargo test --release --test suite NAME::`). One binary links the library and its
//! dependencies once instead of once a file, and its tests share one pool of threads:
//! on 2 cores the test step of `.ci/run` compiled for 190-212 s and ran its binaries
//! one after another for 339-372 s with 57 binaries.

mod common;
#[allow(unused)]
mod gen;
mod mutate;

#[path = "agreement.rs"]
mod agreement;
#[path = "bake.rs"]
mod bake;
#[path = "bake_cli.rs"]
mod bake_cli;
#[path = "bake_clip.rs"]
mod bake_clip;
#[path = "bake_export.rs"]
mod bake_export;
#[path = "bake_fidelity.rs"]
mod bake_fidelity;
#[path = "bake_fit.rs"]
mod bake_fit;
#[path = "bake_mesh.rs"]
mod bake_mesh;
#[path = "bake_packed.rs"]
mod bake_packed;
#[path = "bake_refine.rs"]
mod bake_refine;
#[path = "book.rs"]
mod book;
#[path = "cli.rs"]
mod cli;
#[path = "codegen.rs"]
mod codegen;
#[path = "cpu_eval.rs"]
mod cpu_eval;
#[path = "displace.rs"]
mod displace;
#[path = "dual.rs"]
mod dual;
#[path = "examples.rs"]
mod examples;
#[path = "fuzz_smoke.rs"]
mod fuzz_smoke;
#[path = "glb_fuzz.rs"]
mod glb_fuzz;
#[path = "glb_limits.rs"]
mod glb_limits;
#[path = "gpu.rs"]
mod gpu;
#[path = "gpu_atlas.rs"]
mod gpu_atlas;
#[path = "gpu_displace.rs"]
mod gpu_displace;
#[path = "gpu_mesh.rs"]
mod gpu_mesh;
#[path = "gpu_section5.rs"]
mod gpu_section5;
#[path = "grammar.rs"]
mod grammar;
#[path = "guard.rs"]
mod guard;
#[path = "hardening3.rs"]
mod hardening3;
#[path = "harness.rs"]
mod harness;
#[path = "ide.rs"]
mod ide;
#[path = "incremental.rs"]
mod incremental;
#[path = "limits.rs"]
mod limits;
#[path = "logmap.rs"]
mod logmap;
#[path = "lsp.rs"]
mod lsp;
#[path = "lsp_sessions.rs"]
mod lsp_sessions;
#[path = "manifest.rs"]
mod manifest;
#[path = "material_ref.rs"]
mod material_ref;
#[path = "merge.rs"]
mod merge;
#[path = "moving_atlas.rs"]
mod moving_atlas;
#[path = "multiscale.rs"]
mod multiscale;
#[path = "mutations.rs"]
mod mutations;
#[path = "normal_map.rs"]
mod normal_map;
#[path = "params.rs"]
mod params;
#[path = "prune.rs"]
mod prune;
#[path = "random_scenes.rs"]
mod random_scenes;
#[path = "rest_pose.rs"]
mod rest_pose;
#[path = "robustness.rs"]
mod robustness;
#[path = "safety.rs"]
mod safety;
#[path = "scale.rs"]
mod scale;
#[path = "seeds.rs"]
mod seeds;
#[path = "seeds_coverage.rs"]
mod seeds_coverage;
#[path = "seeds_write.rs"]
mod seeds_write;
#[path = "shell_map.rs"]
mod shell_map;
#[path = "textured_csg.rs"]
mod textured_csg;
#[path = "tidy.rs"]
mod tidy;
#[path = "tiles.rs"]
mod tiles;
#[path = "ui.rs"]
mod ui;
#[path = "viewer.rs"]
mod viewer;
#[path = "views.rs"]
mod views;
#[path = "walk_fidelity.rs"]
mod walk_fidelity;
#[path = "web.rs"]
mod web;
