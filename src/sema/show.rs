//! How constants read in messages, hovers and signatures: the one format of a
//! folded value ([`super::Value::display`]) and of a table's default
//! ([`super::builtins::Dflt::display`]).

/// Formats a number compactly: integers without a fraction, others with up to 6 significant decimals.
pub fn fmt_num(x: f64) -> String {
    if x.is_finite() && x == x.trunc() && x.abs() < 1e15 {
        format!("{}", x as i64)
    } else if x.is_finite() && (x.abs() >= 1e15 || x.abs() < 1e-6) {
        // Huge and tiny numbers in scientific notation, not 40 digits or "0".
        format!("{x:e}")
    } else {
        let s = format!("{x:.6}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    }
}

/// Formats a vector: `[1, 0.5, 0]`.
pub fn fmt_vec(v: &[f64]) -> String {
    format!(
        "[{}]",
        v.iter().map(|x| fmt_num(*x)).collect::<Vec<_>>().join(", ")
    )
}
