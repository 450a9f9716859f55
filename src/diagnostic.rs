//! The one plain diagnostic type shared by the CLI, the language server and the tests.
//!
//! A [`Diagnostic`] carries a severity, a stable code (`E0001`, `W0001`, …), a
//! message, a primary label, secondary labels, notes and an optional help line.
//! It knows nothing about how it is shown: [`render`] draws it with
//! codespan-reporting, [`to_json`] turns it into the machine-readable form of
//! `sdfc check --format json`.

use crate::codes;
use crate::span::{LineIndex, Span};
use codespan_reporting::diagnostic as cs;
use codespan_reporting::files::SimpleFile;
use codespan_reporting::term;
use serde::Serialize;

/// How bad a diagnostic is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    /// A fact worth knowing (an `N` code); never fails a check.
    Note,
    /// Probably a mistake (a `W` code); the scene still compiles.
    Warning,
    /// The scene cannot be compiled (an `E` code); the CLI exits with status 1.
    Error,
}

/// A span with a message, pointing into the source.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Label {
    /// The bytes the label points at.
    pub span: Span,
    /// What it says there.
    pub message: String,
}

impl Label {
    /// A label of `message` on `span`.
    pub fn new(span: Span, message: impl Into<String>) -> Self {
        Label {
            span,
            message: message.into(),
        }
    }
}

/// One replacement of source text.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Edit {
    /// The bytes replaced (empty for an insertion).
    pub span: Span,
    /// What replaces them.
    pub text: String,
}

/// A fix that can be applied mechanically (a code action in the editor).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Fix {
    /// What the fix does, as an editor offers it.
    pub title: String,
    /// The replacements, none overlapping.
    pub edits: Vec<Edit>,
}

/// One problem (or fact) about a source file.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Diagnostic {
    /// Error, warning or note.
    pub severity: Severity,
    /// Stable code, see [`crate::codes`].
    pub code: &'static str,
    /// The one-line message.
    pub message: String,
    /// Where in the scene: None for a diagnostic about no place in it (explicitly
    /// unlocated, never a label at byte 0).
    pub primary: Option<Label>,
    /// Other places that explain the problem.
    pub secondary: Vec<Label>,
    /// Background: why this is a problem.
    pub notes: Vec<String>,
    /// What to do about it.
    pub help: Option<String>,
    /// Machine-applicable fixes, offered as code actions.
    pub fixes: Vec<Fix>,
}

impl Diagnostic {
    /// An error with code `code` and `message`, labelled `label` at `span`.
    pub fn error(
        code: &'static str,
        message: impl Into<String>,
        span: Span,
        label: impl Into<String>,
    ) -> Self {
        Self::new(Severity::Error, code, message, span, label)
    }

    /// A warning with code `code` and `message`, labelled `label` at `span`.
    pub fn warning(
        code: &'static str,
        message: impl Into<String>,
        span: Span,
        label: impl Into<String>,
    ) -> Self {
        Self::new(Severity::Warning, code, message, span, label)
    }

    /// A note with code `code` and `message`, labelled `label` at `span`.
    pub fn note_diag(
        code: &'static str,
        message: impl Into<String>,
        span: Span,
        label: impl Into<String>,
    ) -> Self {
        Self::new(Severity::Note, code, message, span, label)
    }

    fn new(
        severity: Severity,
        code: &'static str,
        message: impl Into<String>,
        span: Span,
        label: impl Into<String>,
    ) -> Self {
        Diagnostic {
            severity,
            code,
            message: message.into(),
            primary: Some(Label::new(span, label)),
            secondary: Vec::new(),
            notes: Vec::new(),
            help: None,
            fixes: Vec::new(),
        }
    }

    /// A diagnostic about no place in the scene (a problem of the whole file or of the
    /// compiler itself): rendered without a source excerpt.
    pub fn unlocated(severity: Severity, code: &'static str, message: impl Into<String>) -> Self {
        Diagnostic {
            severity,
            code,
            message: message.into(),
            primary: None,
            secondary: Vec::new(),
            notes: Vec::new(),
            help: None,
            fixes: Vec::new(),
        }
    }

    /// The primary span, when the diagnostic has a place.
    pub fn span(&self) -> Option<Span> {
        self.primary.as_ref().map(|l| l.span)
    }

    /// Adds a secondary label.
    pub fn with_label(mut self, span: Span, message: impl Into<String>) -> Self {
        self.secondary.push(Label::new(span, message));
        self
    }

    /// Adds a note.
    pub fn with_note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(note.into());
        self
    }

    /// Sets the help.
    pub fn with_help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(help.into());
        self
    }

    /// A fix that replaces `span` with `text`.
    pub fn with_fix(
        mut self,
        title: impl Into<String>,
        span: Span,
        text: impl Into<String>,
    ) -> Self {
        self.fixes.push(Fix {
            title: title.into(),
            edits: vec![Edit {
                span,
                text: text.into(),
            }],
        });
        self
    }

    /// "did you mean `best`?" as help, and the fix that replaces the primary span with it.
    pub fn with_suggestion(self, best: &str) -> Self {
        let with_help = self.with_help(format!("did you mean `{best}`?"));
        match with_help.span() {
            Some(span) => with_help.with_fix(format!("replace with `{best}`"), span, best),
            None => with_help,
        }
    }

    /// Whether this is an error.
    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }
}

/// The most characters of the user's text a message quotes.
pub const MAX_QUOTED: usize = 40;

/// The most diagnostics reported for one file; the rest are counted in a final note.
pub const MAX_DIAGNOSTICS: usize = 1000;

/// The user's text as a message quotes it: in quotes with escapes, and cut after
/// [`MAX_QUOTED`] characters, saying how many more there were.
pub fn quote(text: &str) -> String {
    let total = text.chars().count();
    if total <= MAX_QUOTED {
        return format!("{text:?}");
    }
    let head: String = text.chars().take(MAX_QUOTED).collect();
    format!("{head:?}… ({} more characters)", total - MAX_QUOTED)
}

/// Keeps the first [`MAX_DIAGNOSTICS`] diagnostics (already sorted) and replaces the rest
/// with one note that counts them.
pub fn cap(diags: &mut Vec<Diagnostic>) {
    if diags.len() <= MAX_DIAGNOSTICS {
        return;
    }
    let dropped = &diags[MAX_DIAGNOSTICS..];
    let errors = dropped.iter().filter(|d| d.is_error()).count();
    let message = format!(
        "{} more diagnostics ({errors} of them errors) not shown: sdfc reports at most {MAX_DIAGNOSTICS} per file",
        dropped.len()
    );
    diags.truncate(MAX_DIAGNOSTICS);
    diags.push(Diagnostic::unlocated(
        Severity::Note,
        codes::N_TRUNCATED,
        message,
    ));
}

/// Sorts diagnostics by position (unlocated ones first), then severity, so output is
/// stable.
pub fn sort(diags: &mut [Diagnostic]) {
    let key = |d: &Diagnostic| (d.span(), std::cmp::Reverse(d.severity), d.code);
    diags.sort_by(|a, b| key(a).cmp(&key(b)));
}

fn to_codespan(d: &Diagnostic, len: usize) -> cs::Diagnostic<()> {
    let sev = match d.severity {
        Severity::Error => cs::Severity::Error,
        Severity::Warning => cs::Severity::Warning,
        Severity::Note => cs::Severity::Note,
    };
    let clamp = |s: Span| s.start.min(len)..s.end.min(len).max(s.start.min(len));
    let mut labels: Vec<cs::Label<()>> = d
        .primary
        .iter()
        .map(|p| cs::Label::primary((), clamp(p.span)).with_message(&p.message))
        .collect();
    for l in &d.secondary {
        labels.push(cs::Label::secondary((), clamp(l.span)).with_message(&l.message));
    }
    let mut notes: Vec<String> = d.notes.iter().map(|n| format!("note: {n}")).collect();
    if let Some(h) = &d.help {
        notes.push(format!("help: {h}"));
    }
    cs::Diagnostic::new(sev)
        .with_code(d.code)
        .with_message(&d.message)
        .with_labels(labels)
        .with_notes(notes)
}

/// The longest source line a rendered diagnostic quotes, in bytes; a diagnostic on a
/// longer line gives its position in a note instead.
pub const MAX_SNIPPET_LINE: usize = 1000;

/// A diagnostic whose labels sit on over-long lines, without the labels that do, and with
/// their positions in a note (so a 10 MB line is not printed).
fn without_long_lines(d: &Diagnostic, source: &str, index: &LineIndex) -> Option<Diagnostic> {
    let long = |span: Span| {
        let (line, _) = index.line_col(source, span.start.min(source.len()));
        index.line_len(source, line) > MAX_SNIPPET_LINE
    };
    let any = d.primary.iter().chain(&d.secondary).any(|l| long(l.span));
    if !any {
        return None;
    }
    let mut short = d.clone();
    if let Some(p) = short.primary.take_if(|p| long(p.span)) {
        let (line, col) = index.line_col(source, p.span.start.min(source.len()));
        short.notes.insert(
            0,
            format!(
                "at line {}, column {} ({}; the line is too long to show)",
                line + 1,
                col + 1,
                p.message
            ),
        );
    }
    short.secondary.retain(|l| !long(l.span));
    Some(short)
}

/// Renders diagnostics as text, the way `sdfc check` prints them.
pub fn render(file_name: &str, source: &str, diags: &[Diagnostic], color: bool) -> String {
    let index = LineIndex::new(source);
    let shortened: Vec<Option<Diagnostic>> = diags
        .iter()
        .map(|d| without_long_lines(d, source, &index))
        .collect();
    let diags: Vec<&Diagnostic> = diags
        .iter()
        .zip(&shortened)
        .map(|(d, s)| s.as_ref().unwrap_or(d))
        .collect();
    let file = SimpleFile::new(file_name, source);
    let config = term::Config::default();
    let mut out = Vec::new();
    if color {
        let mut writer = term::termcolor::Ansi::new(&mut out);
        for d in diags {
            let _ = term::emit_to_write_style(
                &mut writer,
                &config,
                &file,
                &to_codespan(d, source.len()),
            );
        }
    } else {
        let mut writer = term::termcolor::NoColor::new(&mut out);
        for d in diags {
            let _ = term::emit_to_write_style(
                &mut writer,
                &config,
                &file,
                &to_codespan(d, source.len()),
            );
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

#[derive(Serialize)]
struct JsonPos {
    line: usize,
    column: usize,
}

#[derive(Serialize)]
struct JsonLabel<'a> {
    message: &'a str,
    byte_start: usize,
    byte_end: usize,
    start: JsonPos,
    end: JsonPos,
}

#[derive(Serialize)]
struct JsonDiagnostic<'a> {
    code: &'static str,
    severity: Severity,
    message: &'a str,
    file: &'a str,
    /// The primary span; null for a diagnostic about no place in the file.
    byte_start: Option<usize>,
    byte_end: Option<usize>,
    start: Option<JsonPos>,
    end: Option<JsonPos>,
    labels: Vec<JsonLabel<'a>>,
    notes: &'a [String],
    help: Option<&'a str>,
}

/// One JSON object (a single line) for a diagnostic, as `sdfc check --format json` prints it.
/// Lines and columns are 1-based; columns count Unicode scalar values.
pub fn to_json(file_name: &str, source: &str, d: &Diagnostic) -> String {
    to_json_indexed(file_name, source, &LineIndex::new(source), d)
}

/// [`to_json`] for every diagnostic of a file, indexing its lines once (linear in the
/// file and the number of diagnostics).
pub fn to_json_all(file_name: &str, source: &str, diags: &[Diagnostic]) -> Vec<String> {
    let index = LineIndex::new(source);
    diags
        .iter()
        .map(|d| to_json_indexed(file_name, source, &index, d))
        .collect()
}

fn to_json_indexed(file_name: &str, source: &str, index: &LineIndex, d: &Diagnostic) -> String {
    let pos = |offset: usize| {
        let (line, column) = index.line_col(source, offset);
        JsonPos {
            line: line + 1,
            column: column + 1,
        }
    };
    let mut labels = Vec::new();
    for l in d.primary.iter().chain(&d.secondary) {
        labels.push(JsonLabel {
            message: &l.message,
            byte_start: l.span.start,
            byte_end: l.span.end,
            start: pos(l.span.start),
            end: pos(l.span.end),
        });
    }
    let j = JsonDiagnostic {
        code: d.code,
        severity: d.severity,
        message: &d.message,
        file: file_name,
        byte_start: d.span().map(|s| s.start),
        byte_end: d.span().map(|s| s.end),
        start: d.span().map(|s| pos(s.start)),
        end: d.span().map(|s| pos(s.end)),
        labels,
        notes: &d.notes,
        help: d.help.as_deref(),
    };
    serde_json::to_string(&j).unwrap_or_else(|_| String::from("{}"))
}
