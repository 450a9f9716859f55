//! The formatter shared by `sdfc fmt` and the language server.
//!
//! It works on the lexer's tokens, comments included, so it never loses a
//! comment and never changes what the parser sees: canonical spacing around
//! operators, commas and colons; one statement per line; 4-space indentation
//! inside `{}` blocks; at most one blank line between statements; line breaks
//! inside a statement are kept (with continuation indentation) so long
//! expressions stay readable. Trailing line comments on consecutive lines are
//! aligned. A file with syntax errors is not formatted.

use crate::diagnostic::Diagnostic;
use crate::span::Span;
use crate::syntax::lexer::{lex, Token};
use crate::syntax::parse;

const INDENT: usize = 4;

/// One element of the source, in order: a significant token or a comment.
struct Elem<'a> {
    /// `None` for a comment.
    tok: Option<Token<'a>>,
    text: &'a str,
    /// Line breaks between the previous element (or the file start) and this one.
    newlines: usize,
    line_comment: bool,
}

fn elements(src: &str) -> Vec<Elem<'_>> {
    let lexed = lex(src, &mut Vec::new());
    let mut all: Vec<(Option<Token>, Span, bool)> = lexed
        .tokens
        .iter()
        .map(|(t, s)| (Some(*t), *s, false))
        .chain(lexed.comments.iter().map(|c| (None, c.span, !c.block)))
        .collect();
    all.sort_by_key(|e| e.1.start);
    let mut prev_end = 0;
    all.into_iter()
        .map(|(tok, span, line_comment)| {
            let newlines = src[prev_end..span.start].matches('\n').count();
            prev_end = span.end;
            let text = &src[span.range()];
            let text = if tok.is_none() { text.trim_end() } else { text };
            Elem {
                tok,
                text,
                newlines,
                line_comment,
            }
        })
        .collect()
}

/// Whether a token ends an operand, so that a following `-` is binary.
fn ends_operand(t: Token) -> bool {
    matches!(
        t,
        Token::Ident(_)
            | Token::Number(_)
            | Token::Str(_)
            | Token::True
            | Token::False
            | Token::RParen
            | Token::RBracket
    )
}

fn is_open(t: Token) -> bool {
    matches!(t, Token::LParen | Token::LBracket)
}

fn is_close(t: Token) -> bool {
    matches!(t, Token::RParen | Token::RBracket)
}

/// One output line: its code and an optional trailing line comment.
#[derive(Default)]
struct Line {
    code: String,
    comment: Option<String>,
}

struct Printer<'a> {
    lines: Vec<Line>,
    /// Brace depth.
    depth: usize,
    /// For each open bracket of the current statement, the level of the line it opened on.
    brackets: Vec<usize>,
    /// The continuation level of the current line.
    level: usize,
    /// Inside a statement (since the last `;`, `{` or `}`).
    in_statement: bool,
    /// The next element starts a new line.
    pending_newline: bool,
    /// The last significant token.
    prev: Option<Token<'a>>,
    /// The last element was a unary operator.
    prev_unary: bool,
    /// The last element was a `{` (for `{}` and no blank line after it).
    prev_open_brace: bool,
    /// The last element was a comment.
    prev_comment: bool,
}

impl<'a> Printer<'a> {
    fn current(&mut self) -> &mut Line {
        self.lines.last_mut().expect("at least one line")
    }

    fn current_is_empty(&self) -> bool {
        self.lines.last().is_none_or(|l| l.code.is_empty())
    }

    fn newline(&mut self, blank: bool, level: usize) {
        if !(self.lines.len() == 1 && self.current_is_empty()) {
            if blank {
                self.lines.push(Line::default());
            }
            self.lines.push(Line::default());
        }
        self.level = level;
        let indent = " ".repeat(INDENT * (self.depth + level));
        self.current().code.push_str(&indent);
        self.pending_newline = false;
    }

    /// The continuation level of a new line inside a statement that starts with `t`.
    fn continuation(&self, t: Option<Token>) -> usize {
        match (t, self.brackets.last()) {
            (Some(t), Some(&opened)) if is_close(t) => opened,
            (_, Some(&opened)) => opened + 1,
            (_, None) => 1,
        }
    }

    fn comment(&mut self, e: &Elem) {
        if e.newlines == 0 && !self.current_is_empty() {
            // A trailing comment.
            if e.line_comment {
                self.current().comment = Some(e.text.to_string());
                self.pending_newline = true;
            } else {
                let glue = !matches!(self.prev, Some(t) if is_open(t)) || self.prev_comment;
                let line = self.current();
                if glue && !line.code.ends_with(' ') {
                    line.code.push(' ');
                }
                line.code.push_str(&e.text.replace("\r\n", "\n"));
            }
        } else {
            let blank = e.newlines >= 2 && !self.prev_open_brace;
            let level = if self.in_statement {
                self.continuation(None)
            } else {
                0
            };
            self.newline(blank, level);
            self.current().code.push_str(&e.text.replace("\r\n", "\n"));
            self.pending_newline = e.line_comment;
        }
        self.prev_unary = false;
        self.prev_open_brace = false;
        self.prev_comment = true;
    }

    fn token(&mut self, e: &Elem, t: Token<'a>) {
        let empty_block = t == Token::RBrace && self.prev_open_brace;
        if t == Token::RBrace {
            self.depth = self.depth.saturating_sub(1);
        }
        // Line breaks the author made inside a statement are kept, except where
        // they would separate a token from the punctuation that belongs to it.
        let keep_break = e.newlines > 0
            && (!self.in_statement
                || (!matches!(t, Token::Comma | Token::Semi | Token::Colon | Token::LBrace)
                    && !self.prev_unary
                    && !matches!(self.prev, Some(Token::Dot | Token::Colon))));
        let starts_line = self.lines.is_empty()
            || (!empty_block && (self.pending_newline || t == Token::RBrace || keep_break));
        if self.lines.is_empty() {
            self.lines.push(Line::default());
        }
        if starts_line {
            let blank = e.newlines >= 2
                && !self.in_statement
                && !self.prev_open_brace
                && t != Token::RBrace;
            // A block's `{` pushed to its own line (after a comment) lines up with its `}`.
            let level = if self.in_statement && t != Token::LBrace {
                self.continuation(Some(t))
            } else {
                0
            };
            self.newline(blank, level);
        } else if !empty_block && !self.current_is_empty() && self.space_before(t) {
            self.current().code.push(' ');
        }
        self.current().code.push_str(e.text);

        let unary = matches!(t, Token::Minus | Token::Bang) && !self.prev.is_some_and(ends_operand);
        match t {
            t if is_open(t) => self.brackets.push(self.level),
            t if is_close(t) => {
                self.brackets.pop();
            }
            Token::Semi if self.brackets.is_empty() => {
                self.in_statement = false;
                self.pending_newline = true;
            }
            Token::LBrace => {
                self.depth += 1;
                self.brackets.clear();
                self.in_statement = false;
                self.pending_newline = true;
            }
            Token::RBrace => {
                self.brackets.clear();
                self.in_statement = false;
                self.pending_newline = true;
            }
            _ => self.in_statement = true,
        }
        self.prev = Some(t);
        self.prev_unary = unary;
        self.prev_open_brace = t == Token::LBrace;
        self.prev_comment = false;
    }

    fn space_before(&self, t: Token) -> bool {
        if self.prev_comment {
            return !matches!(
                t,
                Token::Comma | Token::Semi | Token::RParen | Token::RBracket
            );
        }
        if matches!(
            t,
            Token::Comma
                | Token::Semi
                | Token::Colon
                | Token::Dot
                | Token::RParen
                | Token::RBracket
        ) || self.prev_unary
        {
            return false;
        }
        match self.prev {
            Some(Token::LParen | Token::LBracket | Token::Dot) => false,
            Some(Token::Ident(_)) => t != Token::LParen,
            _ => true,
        }
    }

    fn finish(self, crlf: bool) -> String {
        let mut lines = self.lines;
        // Align the trailing comments of consecutive lines.
        let width = |l: &Line| {
            l.code
                .rsplit('\n')
                .next()
                .unwrap_or("")
                .trim_end()
                .chars()
                .count()
        };
        let mut i = 0;
        while i < lines.len() {
            if lines[i].comment.is_none() {
                i += 1;
                continue;
            }
            let mut j = i;
            while j < lines.len() && lines[j].comment.is_some() {
                j += 1;
            }
            let column = lines[i..j].iter().map(width).max().unwrap_or(0) + 2;
            for l in &mut lines[i..j] {
                let pad = column - width(l);
                let code = l.code.trim_end().to_string();
                l.code = format!(
                    "{code}{}{}",
                    " ".repeat(pad),
                    l.comment.take().unwrap_or_default()
                );
            }
            i = j;
        }
        let mut out = String::new();
        for l in &lines {
            out.push_str(l.code.trim_end());
            out.push('\n');
        }
        let out = out.trim_start_matches('\n');
        let mut out = out.trim_end().to_string();
        if !out.is_empty() {
            out.push('\n');
        }
        if crlf {
            out = out.replace('\n', "\r\n");
        }
        out
    }
}

/// Formats a whole file. A file with syntax errors is returned as its
/// diagnostics (the syntax errors only), and must be left as it is.
pub fn format(src: &str) -> Result<String, Vec<Diagnostic>> {
    let mut diags = Vec::new();
    parse(src, &mut diags);
    diags.retain(Diagnostic::is_error);
    if !diags.is_empty() {
        return Err(diags);
    }
    let crlf = src.find('\n').is_some_and(|i| src[..i].ends_with('\r'));
    let mut p = Printer {
        lines: Vec::new(),
        depth: 0,
        brackets: Vec::new(),
        level: 0,
        in_statement: false,
        pending_newline: false,
        prev: None,
        prev_unary: false,
        prev_open_brace: false,
        prev_comment: false,
    };
    for e in elements(src) {
        match e.tok {
            Some(t) => p.token(&e, t),
            None => {
                if p.lines.is_empty() {
                    p.lines.push(Line::default());
                }
                p.comment(&e)
            }
        }
    }
    let out = p.finish(crlf);
    // A byte-order mark is kept: the lexer skips it, so the printer never sees it.
    if src.starts_with(crate::syntax::source::BOM) {
        return Ok(format!("{}{out}", crate::syntax::source::BOM));
    }
    Ok(out)
}

/// The smallest single edit that turns `old` into `new`: the byte range of
/// `old` to replace, and its replacement. `None` when they are equal.
pub fn minimal_edit(old: &str, new: &str) -> Option<(Span, String)> {
    if old == new {
        return None;
    }
    let mut start = old
        .bytes()
        .zip(new.bytes())
        .take_while(|(a, b)| a == b)
        .count();
    while !old.is_char_boundary(start) || !new.is_char_boundary(start) {
        start -= 1;
    }
    let max_suffix = old.len().min(new.len()) - start;
    let mut suffix = old
        .bytes()
        .rev()
        .zip(new.bytes().rev())
        .take(max_suffix)
        .take_while(|(a, b)| a == b)
        .count();
    while !old.is_char_boundary(old.len() - suffix) || !new.is_char_boundary(new.len() - suffix) {
        suffix -= 1;
    }
    Some((
        Span::new(start, old.len() - suffix),
        new[start..new.len() - suffix].to_string(),
    ))
}
