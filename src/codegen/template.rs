//! WGSL templates: real WGSL files in `shaders/` with named `{{placeholders}}`, filled
//! by code generation. A template names each of its placeholders; filling checks that
//! every placeholder gets a value and every value has a placeholder, so a template and
//! its emitter cannot drift apart silently.

/// The code of one atlas (its field, walk, Alg. 2): `shaders/atlas.wgsl.in`.
pub const ATLAS: &str = include_str!("../../shaders/atlas.wgsl.in");
/// An atlas's refinement (`refine` > 0): `shaders/refine.wgsl.in`.
pub const REFINE: &str = include_str!("../../shaders/refine.wgsl.in");
/// The scene-independent tail of every module (tracing, normals, entry points).
pub const ENTRY: &str = include_str!("../../shaders/entry.wgsl.in");
/// The trace's marches over one field (`codegen::tiles`): `shaders/trace.wgsl.in`.
pub const TRACE: &str = include_str!("../../shaders/trace.wgsl.in");
/// The multi-scale atlas pass (`Options::multiscale`): `shaders/coarse.wgsl.in`.
pub const COARSE: &str = include_str!("../../shaders/coarse.wgsl.in");
/// A baked mesh's renderer, with the flat layout's constants.
pub const MESH: &str = include_str!("../../shaders/mesh.wgsl.in");
/// A fragment entry point writing the AOVs as the bits of their floats (rgba32uint
/// targets), for adapters without rgba32float targets: `shaders/aov_bits.wgsl.in`.
pub const AOV_BITS: &str = include_str!("../../shaders/aov_bits.wgsl.in");

/// The placeholders of a template, in order of first use.
pub fn placeholders(template: &str) -> Vec<&str> {
    let mut out: Vec<&str> = Vec::new();
    let mut rest = template;
    while let Some(open) = rest.find("{{") {
        let after = &rest[open + 2..];
        let Some(close) = after.find("}}") else {
            break;
        };
        let name = &after[..close];
        if !out.contains(&name) {
            out.push(name);
        }
        rest = &after[close + 2..];
    }
    out
}

/// A template and the values of its placeholders did not match (a bug in sdfc).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Mismatch {
    /// Placeholders of the template with no value.
    pub missing: Vec<String>,
    /// Values for no placeholder of the template.
    pub unused: Vec<String>,
}

impl std::fmt::Display for Mismatch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "template placeholders without a value: [{}]; values without a placeholder: [{}]",
            self.missing.join(", "),
            self.unused.join(", ")
        )
    }
}

/// Fills every `{{name}}` of `template` with its value.
pub fn fill(template: &str, values: &[(&str, String)]) -> Result<String, Mismatch> {
    let names = placeholders(template);
    let missing: Vec<String> = names
        .iter()
        .filter(|n| !values.iter().any(|(k, _)| k == *n))
        .map(|n| n.to_string())
        .collect();
    let unused: Vec<String> = values
        .iter()
        .filter(|(k, _)| !names.contains(k))
        .map(|(k, _)| k.to_string())
        .collect();
    if !missing.is_empty() || !unused.is_empty() {
        return Err(Mismatch { missing, unused });
    }
    let mut out = String::with_capacity(template.len() * 2);
    let mut rest = template;
    while let Some(open) = rest.find("{{") {
        out.push_str(&rest[..open]);
        let after = &rest[open + 2..];
        let close = after.find("}}").unwrap_or(after.len());
        let name = &after[..close];
        if let Some((_, v)) = values.iter().find(|(k, _)| *k == name) {
            out.push_str(v);
        }
        rest = after.get(close + 2..).unwrap_or("");
    }
    out.push_str(rest);
    Ok(out)
}
