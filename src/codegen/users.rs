//! Which entry points use which binding, derived from the validated module: an entry
//! point uses a binding when its function, or a function it calls (transitively),
//! refers to the binding's global variable. The manifest's `used_by` and the header
//! say exactly that, so a host that builds one bind group layout per entry point from
//! the manifest builds every pipeline (a displacement's texture, sampled inside
//! `scene_map`, is used by `cs_points` and `cs_grid` too).

use naga::{Block, Function, Handle, Module, Statement};
use std::collections::HashSet;

/// For each entry point of `module` (by name), the `(group, binding)` pairs it uses.
pub fn entry_bindings(module: &Module) -> Vec<(String, HashSet<(u32, u32)>)> {
    module
        .entry_points
        .iter()
        .map(|ep| {
            let mut seen = HashSet::new();
            let mut used = HashSet::new();
            visit(module, &ep.function, &mut seen, &mut used);
            (ep.name.clone(), used)
        })
        .collect()
}

/// Adds the bindings `f` refers to, and those of every function it calls.
fn visit(
    module: &Module,
    f: &Function,
    seen: &mut HashSet<Handle<Function>>,
    used: &mut HashSet<(u32, u32)>,
) {
    for (_, e) in f.expressions.iter() {
        if let naga::Expression::GlobalVariable(g) = e {
            if let Some(b) = &module.global_variables[*g].binding {
                used.insert((b.group, b.binding));
            }
        }
    }
    let mut calls = Vec::new();
    calls_in(&f.body, &mut calls);
    for c in calls {
        if seen.insert(c) {
            visit(module, &module.functions[c], seen, used);
        }
    }
}

/// The functions a block calls, nested blocks included.
fn calls_in(block: &Block, out: &mut Vec<Handle<Function>>) {
    for s in block.iter() {
        match s {
            Statement::Call { function, .. } => out.push(*function),
            Statement::Block(b) => calls_in(b, out),
            Statement::If { accept, reject, .. } => {
                calls_in(accept, out);
                calls_in(reject, out);
            }
            Statement::Switch { cases, .. } => {
                for c in cases {
                    calls_in(&c.body, out);
                }
            }
            Statement::Loop {
                body, continuing, ..
            } => {
                calls_in(body, out);
                calls_in(continuing, out);
            }
            _ => {}
        }
    }
}
