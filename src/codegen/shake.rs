//! Tree shaking of the shared WGSL library, on its text, before naga sees the module.
//!
//! Every module used to carry the whole library (`shaders/sdf.wgsl`, `render.wgsl`,
//! `uv.wgsl`), and naga's WGSL front end, which costs about 100 ns per byte, parsed all
//! of it for every compile, only for `sdfc compile` to compact the unused part away
//! again. Here the library is split once into its top-level items; a module gets the
//! library's functions that its generated code reaches, directly or through other
//! library functions, and every other item (structs, constants, private variables) as
//! it is. What naga validates is then the text that is written out.
//!
//! References are found by identifiers, so a local variable or a member named like a
//! library function keeps that function: shaking may keep too much, never too little
//! (naga would reject the module, an internal compiler error the tests would catch).

use std::collections::HashMap;
use std::ops::ControlFlow;
use std::sync::OnceLock;

/// One top-level item of the library, with the comments and blank lines before it.
#[derive(Debug)]
struct Item {
    range: std::ops::Range<usize>,
    /// `Some(name)` for a function without attributes, which is kept only when reached.
    function: Option<String>,
    /// The library functions this item names (indices into the items).
    calls: Vec<usize>,
}

struct Library {
    text: String,
    items: Vec<Item>,
    /// Function name → item index.
    functions: HashMap<String, usize>,
}

fn library() -> &'static Library {
    static LIBRARY: OnceLock<Library> = OnceLock::new();
    LIBRARY.get_or_init(|| {
        let text = format!(
            "{}\n{}\n{}\n{}\n",
            super::SDF_LIBRARY,
            super::RENDER_LIBRARY,
            super::UV_LIBRARY,
            super::DUAL_LIBRARY
        );
        let mut items: Vec<Item> = split(&text)
            .into_iter()
            .map(|range| Item {
                function: function_name(&text[range.clone()]),
                range,
                calls: Vec::new(),
            })
            .collect();
        let functions: HashMap<String, usize> = items
            .iter()
            .enumerate()
            .filter_map(|(i, item)| item.function.clone().map(|n| (n, i)))
            .collect();
        for item in &mut items {
            let mut calls: Vec<usize> = Vec::new();
            for_each_identifier(&text[item.range.clone()], |id| {
                if let Some(&i) = functions.get(id) {
                    if !calls.contains(&i) {
                        calls.push(i);
                    }
                }
            });
            item.calls = calls;
        }
        Library {
            text,
            items,
            functions,
        }
    })
}

/// The whole library, unshaken, as modules carried it before (for measurements and
/// tests).
pub fn full_library() -> &'static str {
    &library().text
}

/// The library's part of a module whose generated code is `code`: every item but the
/// functions that nothing in `code` reaches, in the library's order.
pub fn library_for(code: &str) -> String {
    let lib = library();
    let mut keep = vec![false; lib.items.len()];
    let mut stack: Vec<usize> = Vec::new();
    for (i, item) in lib.items.iter().enumerate() {
        if item.function.is_none() {
            stack.push(i);
        }
    }
    for_each_identifier(code, |id| {
        if let Some(&i) = lib.functions.get(id) {
            stack.push(i);
        }
    });
    while let Some(i) = stack.pop() {
        if std::mem::replace(&mut keep[i], true) {
            continue;
        }
        stack.extend(lib.items[i].calls.iter().filter(|&&c| !keep[c]));
    }
    let mut out = String::with_capacity(lib.text.len());
    for (item, kept) in lib.items.iter().zip(keep) {
        if kept {
            out.push_str(&lib.text[item.range.clone()]);
        }
    }
    out
}

/// Splits WGSL text into top-level items: each range runs from the end of the previous
/// item (so it holds the comments before its item) to the `;` or closing `}` that ends
/// the item at depth 0, and the rest of that line. Text after the last item is a range
/// of its own. The ranges cover the text, in order.
fn split(text: &str) -> Vec<std::ops::Range<usize>> {
    let bytes = text.as_bytes();
    let mut ranges = Vec::new();
    let (mut start, mut i, mut depth) = (0usize, 0usize, 0usize);
    let mut seen_code = false;
    while i < bytes.len() {
        match bytes[i] {
            b'/' if matches!(bytes.get(i + 1), Some(b'/' | b'*')) => {
                i = comment_end(bytes, i);
                continue;
            }
            b'{' => depth += 1,
            b'}' => depth = depth.saturating_sub(1),
            _ => {}
        }
        let c = bytes[i];
        if !c.is_ascii_whitespace() {
            seen_code = true;
        }
        if depth == 0 && seen_code && (c == b';' || c == b'}') {
            let mut end = i + 1;
            while end < bytes.len() && bytes[end] != b'\n' {
                end += 1;
            }
            end = (end + 1).min(bytes.len());
            ranges.push(start..end);
            start = end;
            i = end;
            seen_code = false;
            continue;
        }
        i += 1;
    }
    if start < bytes.len() {
        ranges.push(start..bytes.len());
    }
    ranges
}

/// The end of the comment starting at `i` (`//` to the end of its line; `/*` to its
/// closing `*/`, nested as WGSL nests them), or of the text.
fn comment_end(bytes: &[u8], mut i: usize) -> usize {
    if bytes[i..].starts_with(b"//") {
        while i < bytes.len() && bytes[i] != b'\n' {
            i += 1;
        }
        return i;
    }
    let mut nest = 0usize;
    while i < bytes.len() {
        if bytes[i..].starts_with(b"/*") {
            nest += 1;
            i += 2;
        } else if bytes[i..].starts_with(b"*/") {
            nest -= 1;
            i += 2;
            if nest == 0 {
                break;
            }
        } else {
            i += 1;
        }
    }
    i
}

/// The name of a function item without attributes (`fn NAME(`); None for anything
/// else, which is always kept (attributes mark entry points and bindings).
fn function_name(item: &str) -> Option<String> {
    let mut words: Vec<&str> = Vec::with_capacity(2);
    for_each_token(item, |t| {
        words.push(t);
        if words.len() == 2 {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    });
    match words.as_slice() {
        ["fn", name] => Some(name.to_string()),
        _ => None,
    }
}

/// Calls `f` with each identifier of WGSL text, outside comments.
fn for_each_identifier(text: &str, mut f: impl FnMut(&str)) {
    for_each_token(text, |t| {
        if t.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_') {
            f(t)
        }
        ControlFlow::Continue(())
    });
}

/// Calls `f` with each word (identifier or number) and each other non-space character
/// of WGSL text, outside comments, until it breaks.
fn for_each_token<'a>(text: &'a str, mut f: impl FnMut(&'a str) -> ControlFlow<()>) {
    let bytes = text.as_bytes();
    let mut i = 0;
    while i < bytes.len() {
        let c = bytes[i];
        if c == b'/' && matches!(bytes.get(i + 1), Some(b'/' | b'*')) {
            i = comment_end(bytes, i);
        } else if c.is_ascii_alphanumeric() || c == b'_' {
            let start = i;
            while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                i += 1;
            }
            if f(&text[start..i]).is_break() {
                return;
            }
        } else {
            if !c.is_ascii_whitespace() && c.is_ascii() && f(&text[i..i + 1]).is_break() {
                return;
            }
            i += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn items_cover_the_library_in_order() {
        let lib = library();
        let mut at = 0;
        for item in &lib.items {
            assert_eq!(item.range.start, at);
            at = item.range.end;
        }
        assert_eq!(at, lib.text.len());
        // Every `fn` at the start of a line is one item's function.
        let declared = lib.text.lines().filter(|l| l.starts_with("fn ")).count();
        assert_eq!(lib.functions.len(), declared);
        assert!(
            lib.functions.contains_key("sd_sphere") && lib.functions.contains_key("uv_step_chord")
        );
    }

    #[test]
    fn a_function_brings_what_it_calls_and_nothing_else() {
        let shaken = library_for("fn map(p: vec3<f32>) -> f32 { return sd_sphere(p, 1.0); }");
        assert!(shaken.contains("fn sd_sphere("));
        assert!(!shaken.contains("fn sd_torus(") && !shaken.contains("fn uv_step_chord("));
        // Structs and constants stay.
        assert!(shaken.contains("struct Globals {") && shaken.contains("const UV_OK"));
        // Names in comments are no references.
        let commented = library_for("// sd_torus\n/* sd_box /* nested */ sd_torus */");
        assert!(!commented.contains("fn sd_torus(") && !commented.contains("fn sd_box("));
        // Calls reach through the library: the chord step needs its helpers.
        let walk = library_for("let s = uv_step_chord(a, b, c);");
        let lib = library();
        for &c in &lib.items[lib.functions["uv_step_chord"]].calls {
            let name = lib.items[c].function.as_deref().unwrap();
            assert!(walk.contains(&format!("fn {name}(")), "{name}");
        }
    }

    #[test]
    fn splitting_keeps_comments_with_the_item_after_them() {
        let text = "// a\nfn a() {\n    { }\n}\n/* b { */\nconst B: u32 = 1u; // tail\n\n// end\n";
        let parts: Vec<&str> = split(text).into_iter().map(|r| &text[r]).collect();
        assert_eq!(
            parts,
            [
                "// a\nfn a() {\n    { }\n}\n",
                "/* b { */\nconst B: u32 = 1u; // tail\n",
                "\n// end\n"
            ]
        );
        assert_eq!(function_name(parts[0]).as_deref(), Some("a"));
        assert_eq!(function_name(parts[1]), None);
        assert_eq!(
            function_name("@compute @workgroup_size(1) fn main() {}"),
            None
        );
    }
}
