//! How big a value is once its `let`s are inlined. Values share the nodes of the `let`s
//! they use (a DAG), but lowering and evaluation see trees, so both the depth and the
//! expanded size are bounded here, when each `let` is defined, with a spanned error.
//! Measuring is linear in the DAG: every shared node is measured once.

use super::types::{FieldExpr, Value};
use std::collections::HashMap;

/// The deepest a value may be with its `let`s inlined (levels of nodes).
pub const MAX_INLINED_DEPTH: u32 = 512;
/// The most nodes a value may have with its `let`s inlined.
pub const MAX_INLINED_SIZE: u64 = 100_000;

/// Depth and expanded size of a value, memoized by node.
#[derive(Default)]
pub struct Sizes {
    memo: HashMap<*const (), (u32, u64)>,
}

impl Sizes {
    /// (depth, expanded size) of `v`; both saturate.
    pub fn measure(&mut self, v: &Value) -> (u32, u64) {
        let (key, children): (*const (), Vec<&Value>) = match v {
            Value::Shape(n) | Value::Texture(n) => (
                std::sync::Arc::as_ptr(n) as *const (),
                n.args.iter().collect(),
            ),
            Value::Field(e, _) => (
                std::sync::Arc::as_ptr(e) as *const (),
                match &**e {
                    FieldExpr::Input(_) | FieldExpr::Param(_) | FieldExpr::Atlas { .. } => {
                        Vec::new()
                    }
                    FieldExpr::Unary { operand, .. } => vec![operand],
                    FieldExpr::Binary { lhs, rhs, .. } => vec![lhs, rhs],
                    FieldExpr::Swizzle { base, .. } => vec![base],
                    FieldExpr::Call { args, .. } | FieldExpr::Vector(args) => args.iter().collect(),
                },
            ),
            _ => return (1, 1),
        };
        if let Some(&m) = self.memo.get(&key) {
            return m;
        }
        let (mut depth, mut size) = (0u32, 1u64);
        for c in children {
            let (d, s) = stacker::maybe_grow(64 * 1024, 1024 * 1024, || self.measure(c));
            depth = depth.max(d);
            size = size.saturating_add(s);
        }
        let m = (depth.saturating_add(1), size);
        self.memo.insert(key, m);
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sema::builtins::BuiltinId;
    use crate::sema::types::Node;
    use crate::span::Span;
    use std::sync::Arc;

    #[test]
    fn shared_nodes_count_once_per_use_but_are_measured_once() {
        let leaf = Value::Shape(Arc::new(Node {
            builtin: BuiltinId::Sphere,
            args: vec![Value::Float(1.0)],
            span: Span::new(0, 0),
        }));
        let mut v = leaf;
        for _ in 0..40 {
            v = Value::Shape(Arc::new(Node {
                builtin: BuiltinId::Union,
                args: vec![v.clone(), v],
                span: Span::new(0, 0),
            }));
        }
        let mut sizes = Sizes::default();
        let (depth, size) = sizes.measure(&v);
        assert_eq!(depth, 42);
        // 2^41 + … nodes: far beyond the limit, measured in 41 steps.
        assert!(size > 1u64 << 40);
        assert!(sizes.memo.len() <= 42);
    }
}
