//! The size of each entry point once every call is inlined: what a driver's shader
//! compiler builds (Mesa's gallivm and most GPU compilers inline every WGSL function).
//!
//! A walk nested inside another walk (an atlas on a displaced shape, whose every field
//! evaluation walks the height's atlas) multiplies: each call site of a function is
//! one more copy of its body, so an outer walk that differentiates a displaced field
//! holds a copy of the inner walk per evaluation. The WGSL text stays small (60 to
//! 75 KB) while the inlined code runs to millions of expressions; lavapipe then spent
//! 117 s and 4.9 GB on one such pipeline and ran out of 24 GB on a slightly larger
//! one. The compiler refuses modules over [`MAX_INLINED`] with a spanned error
//! (E0118) instead of handing the driver what it cannot build.

use naga::{Block, Function, Handle, Module, Statement};
use std::collections::HashMap;

/// The largest loop-weighted inlined size ([`weighted`]) an entry point may have.
/// Measured on lavapipe (LLVM 15, 2 cores, whole `sdfc render --size 64x48`), build
/// time and memory grow with it: the unrolled robot (the largest example, 6.0 M)
/// takes 2.6 s; an atlas on a displaced sphere read by a material (tests/displace.rs,
/// 39 M with the loop walk) 6 s and 0.7 GB; the shell map of a displaced sphere read
/// through a second atlas on it (435 M with the loop walk) 117-151 s and 5 GB. The
/// limit leaves the examples a margin of 10 and refuses what would take lavapipe
/// over about 20 s.
pub const MAX_INLINED: u64 = 64_000_000;

/// How much more an expression inside one more loop counts: the fit of lavapipe's
/// build times above (a driver's loop passes, unrolling and lane masks work on every
/// level of nesting again).
pub const LOOP_WEIGHT: u64 = 4;

/// A profile's loop-weighted size: Σ expressions at loop depth d × [`LOOP_WEIGHT`]^d.
pub fn weighted(profile: &[u64]) -> u64 {
    let mut w = 1u64;
    let mut total = 0u64;
    for n in profile {
        total = total.saturating_add(n.saturating_mul(w));
        w = w.saturating_mul(LOOP_WEIGHT);
    }
    total
}

/// Each entry point's name with its loop-weighted inlined size, largest first.
pub fn inlined_sizes(module: &Module) -> Vec<(String, u64)> {
    let mut out: Vec<(String, u64)> = by_loop_depth(module)
        .into_iter()
        .map(|(e, p)| (e, weighted(&p)))
        .collect();
    out.sort_by(|a, b| b.1.cmp(&a.1).then_with(|| a.0.cmp(&b.0)));
    out
}

/// Each entry point's inlined expressions by loop depth (index d: inside d loops,
/// counting the loops of inlined callees at the depth of their call), largest total first.
pub fn by_loop_depth(module: &Module) -> Vec<(String, Vec<u64>)> {
    let mut memo: HashMap<Handle<Function>, Vec<u64>> = HashMap::new();
    for (h, f) in module.functions.iter() {
        let profile = function_profile(f, &memo);
        memo.insert(h, profile);
    }
    let mut out: Vec<(String, Vec<u64>)> = module
        .entry_points
        .iter()
        .map(|e| (e.name.clone(), function_profile(&e.function, &memo)))
        .collect();
    out.sort_by_key(|(_, p)| std::cmp::Reverse(p.iter().sum::<u64>()));
    out
}

fn function_profile(f: &Function, memo: &HashMap<Handle<Function>, Vec<u64>>) -> Vec<u64> {
    // The function's own expressions at depth 0 (naga keeps one arena per function,
    // without the statement each belongs to), a unit per loop at its depth, and each
    // call site a copy of the callee's profile at the call's depth.
    let mut out = vec![f.expressions.len() as u64];
    block_profile(&f.body, 0, memo, &mut out);
    out
}

fn add_at(out: &mut Vec<u64>, depth: usize, profile: &[u64]) {
    if out.len() < depth + profile.len() {
        out.resize(depth + profile.len(), 0);
    }
    for (d, n) in profile.iter().enumerate() {
        out[depth + d] = out[depth + d].saturating_add(*n);
    }
}

fn block_profile(
    block: &Block,
    depth: usize,
    memo: &HashMap<Handle<Function>, Vec<u64>>,
    out: &mut Vec<u64>,
) {
    for s in block.iter() {
        match s {
            Statement::Call { function, .. } => {
                if let Some(p) = memo.get(function) {
                    add_at(out, depth, p);
                }
            }
            Statement::Block(b) => block_profile(b, depth, memo, out),
            Statement::If { accept, reject, .. } => {
                block_profile(accept, depth, memo, out);
                block_profile(reject, depth, memo, out);
            }
            Statement::Switch { cases, .. } => {
                for c in cases {
                    block_profile(&c.body, depth, memo, out);
                }
            }
            Statement::Loop {
                body, continuing, ..
            } => {
                add_at(out, depth + 1, &[1]);
                block_profile(body, depth + 1, memo, out);
                block_profile(continuing, depth + 1, memo, out);
            }
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn profile(wgsl: &str) -> Vec<u64> {
        let m = naga::front::wgsl::parse_str(wgsl).expect("valid WGSL");
        by_loop_depth(&m).into_iter().next().unwrap().1
    }

    const F: &str = "fn f(x: f32) -> f32 { return x * 2.0 + 1.0; }\n";

    #[test]
    fn every_call_site_is_a_copy_of_the_callee_at_its_loop_depth() {
        let f = naga::front::wgsl::parse_str(F).unwrap();
        let f_size = f.functions.iter().next().unwrap().1.expressions.len() as u64;
        // main calls g twice (once inside an if), g calls f three times: six copies.
        let flat = profile(&format!(
            "{F}fn g(x: f32) -> f32 {{ return f(x) + f(x + 1.0) + f(x + 2.0); }}\n\
             @compute @workgroup_size(1) fn main() {{ let a = g(1.0); if (a > 0.0) {{ let b = g(a); }} }}"
        ));
        assert_eq!(flat.len(), 1, "{flat:?}");
        assert!(
            flat[0] >= 6 * f_size && flat[0] < 6 * f_size + 60,
            "{flat:?} vs {f_size}"
        );
        // A call in a loop of a function called in a loop is at depth 2.
        let nested = profile(&format!(
            "{F}fn g(x: f32) -> f32 {{ var s = 0.0; for (var i = 0; i < 4; i++) {{ s += f(s); }} return s; }}\n\
             @compute @workgroup_size(1) fn main() {{ var t = 0.0; loop {{ t += g(t); if (t > 9.0) {{ break; }} }} }}"
        ));
        assert_eq!(nested.len(), 3, "{nested:?}");
        assert!(nested[2] >= f_size, "{nested:?}");
        let w = weighted(&nested);
        assert_eq!(
            w,
            nested[0] + LOOP_WEIGHT * nested[1] + LOOP_WEIGHT * LOOP_WEIGHT * nested[2]
        );
    }
}
