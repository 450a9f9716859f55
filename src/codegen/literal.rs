//! WGSL literals for constants: the generator's one way of writing a number.

use glam::DVec3;

/// A WGSL float literal for a constant (always with a decimal point or exponent).
pub fn lit(x: f64) -> String {
    let x = x as f32;
    let s = format!("{x:?}");
    let s = if s.contains('.') || s.contains('e') || s.contains("inf") || s.contains("NaN") {
        s
    } else {
        format!("{s}.0")
    };
    if x < 0.0 {
        format!("({s})")
    } else {
        s
    }
}

/// A literal as a function argument or array element: no parentheses around a
/// negative one (naga's parser takes each through its whole precedence chain again).
pub fn arg(x: f64) -> String {
    let s = lit(x);
    match s.strip_prefix('(').and_then(|s| s.strip_suffix(')')) {
        Some(inner) => inner.to_string(),
        None => s,
    }
}

/// A `vec3f` constant (the alias parses as one token; `vec3<f32>` as four).
pub fn vec3(v: DVec3) -> String {
    format!("vec3f({}, {}, {})", arg(v.x), arg(v.y), arg(v.z))
}
