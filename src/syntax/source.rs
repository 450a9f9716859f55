//! Source text from bytes: UTF-8 with an optional byte-order mark, under a size limit.

use crate::codes;
use crate::diagnostic::Diagnostic;
use crate::span::Span;

/// The largest scene file sdfc reads, in bytes (also the language server's document limit).
pub const MAX_SOURCE_BYTES: usize = 8 << 20;

/// The UTF-8 byte-order mark that Windows editors write; the lexer skips it.
pub const BOM: char = '\u{feff}';

/// Decodes a file's bytes. Invalid UTF-8 sequences become U+FFFD (3 bytes in the text),
/// each with a spanned error that gives its byte offset in the file.
pub fn decode(bytes: &[u8]) -> (String, Vec<Diagnostic>) {
    if let Ok(text) = std::str::from_utf8(bytes) {
        return (text.to_string(), Vec::new());
    }
    let mut text = String::with_capacity(bytes.len() + 16);
    // Runs of invalid sequences: (start in the text, end in the text, offset in the file,
    // the bytes).
    let mut runs: Vec<(usize, usize, usize, Vec<u8>)> = Vec::new();
    let mut offset = 0;
    for chunk in bytes.utf8_chunks() {
        text.push_str(chunk.valid());
        offset += chunk.valid().len();
        let invalid = chunk.invalid();
        if invalid.is_empty() {
            continue;
        }
        let start = text.len();
        text.push(char::REPLACEMENT_CHARACTER);
        match runs.last_mut() {
            Some(run) if run.1 == start => {
                run.1 = text.len();
                run.3.extend(invalid);
            }
            _ => runs.push((start, text.len(), offset, invalid.to_vec())),
        }
        offset += invalid.len();
    }
    let diags = runs
        .into_iter()
        .map(|(start, end, offset, bytes)| {
            let mut hex: Vec<String> = bytes.iter().take(8).map(|b| format!("{b:#04x}")).collect();
            if bytes.len() > 8 {
                hex.push(format!("… ({} bytes)", bytes.len()));
            }
            Diagnostic::error(
                codes::E_INVALID_UTF8,
                format!("invalid UTF-8 at byte {offset}: {}", hex.join(" ")),
                Span::new(start, end),
                "not UTF-8",
            )
            .with_note("scene files are UTF-8 text; save the file as UTF-8")
        })
        .collect();
    (text, diags)
}

/// The error for a source over [`MAX_SOURCE_BYTES`], or None.
pub fn too_large(text: &str) -> Option<Diagnostic> {
    (text.len() > MAX_SOURCE_BYTES).then(|| {
        Diagnostic::unlocated(
            crate::diagnostic::Severity::Error,
            codes::E_TOO_LARGE,
            format!(
                "the file is larger than the limit of {} MiB ({MAX_SOURCE_BYTES} bytes); it is not checked",
                MAX_SOURCE_BYTES >> 20
            ),
        )
    })
}
