//! The lexer: text → tokens, built on logos.
//!
//! Lexing never stops: anything logos cannot match becomes [`Token::Error`]
//! and is reported once; comments are kept aside as trivia for the formatter.

use crate::codes;
use crate::diagnostic::Diagnostic;
use crate::span::Span;
use logos::Logos;
use std::fmt;

fn block_comment<'a>(lex: &mut logos::Lexer<'a, Token<'a>>) -> bool {
    match lex.remainder().find("*/") {
        Some(i) => {
            lex.bump(i + 2);
            true
        }
        None => {
            let n = lex.remainder().len();
            lex.bump(n);
            false
        }
    }
}

/// A token of the scene language.
#[derive(Logos, Debug, Clone, Copy, PartialEq)]
#[logos(skip r"[ \t\r\n\f]+")]
pub enum Token<'a> {
    /// Anything the lexer could not match.
    Error,

    #[token("let")]
    Let,
    #[token("param")]
    Param,
    #[token("in")]
    In,
    #[token("atlas")]
    Atlas,
    #[token("material")]
    Material,
    #[token("render")]
    Render,
    #[token("on")]
    On,
    #[token("seed")]
    Seed,
    #[token("tangent")]
    Tangent,
    #[token("merge")]
    Merge,
    #[token("true")]
    True,
    #[token("false")]
    False,

    #[regex(r"[A-Za-z_][A-Za-z0-9_]*")]
    Ident(&'a str),
    /// A number with an optional `deg`/`rad` unit suffix, kept as text.
    #[regex(r"[0-9]+(\.[0-9]+)?([eE][+-]?[0-9]+)?(deg|rad)?")]
    Number(&'a str),
    /// A number whose exponent has no digits, such as `1e` or `2.5e+`.
    #[regex(r"[0-9]+(\.[0-9]+)?[eE][+-]?")]
    BadNumber(&'a str),
    /// A string literal with its quotes.
    #[regex(r#""([^"\\\n]|\\[^\n])*""#)]
    Str(&'a str),
    /// A string literal that reaches the end of its line.
    #[regex(r#""([^"\\\n]|\\[^\n])*"#)]
    UnterminatedStr(&'a str),

    #[regex(r"//[^\n]*", allow_greedy = true)]
    LineComment(&'a str),
    /// `/* … */`; false when it never ends.
    #[token("/*", block_comment)]
    BlockComment(bool),

    #[token("(")]
    LParen,
    #[token(")")]
    RParen,
    #[token("[")]
    LBracket,
    #[token("]")]
    RBracket,
    #[token("{")]
    LBrace,
    #[token("}")]
    RBrace,
    #[token(",")]
    Comma,
    #[token(";")]
    Semi,
    #[token(":")]
    Colon,
    #[token(".")]
    Dot,
    #[token("=")]
    Assign,
    #[token("+")]
    Plus,
    #[token("-")]
    Minus,
    #[token("*")]
    Star,
    #[token("/")]
    Slash,
    #[token("%")]
    Percent,
    #[token("|")]
    Pipe,
    #[token("&")]
    Amp,
    #[token("!")]
    Bang,
    #[token("==")]
    EqEq,
    #[token("!=")]
    NotEq,
    #[token("<")]
    Lt,
    #[token("<=")]
    Le,
    #[token(">")]
    Gt,
    #[token(">=")]
    Ge,
}

/// Every keyword of the language, in the order the grammar lists them.
/// The TextMate grammar's keyword list is tested against this.
pub const KEYWORDS: &[&str] = &[
    "let", "param", "atlas", "material", "render", "on", "in", "seed", "tangent", "merge", "true",
    "false",
];

impl Token<'_> {
    /// Keywords that start a top-level item. Elsewhere they appear only as names after
    /// `.` or before `:` (`x.material`, `paint(material: m)`), so the parser splits the
    /// file at them, outside those places, to keep errors independent.
    pub fn starts_item(&self) -> bool {
        matches!(
            self,
            Token::Let | Token::Param | Token::Atlas | Token::Material | Token::Render
        )
    }

    /// The binary operators (`-` is also unary).
    pub fn is_binary_operator(&self) -> bool {
        matches!(
            self,
            Token::Plus
                | Token::Minus
                | Token::Star
                | Token::Slash
                | Token::Percent
                | Token::Pipe
                | Token::Amp
                | Token::EqEq
                | Token::NotEq
                | Token::Lt
                | Token::Le
                | Token::Gt
                | Token::Ge
        )
    }
}

impl fmt::Display for Token<'_> {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        let s = match self {
            Token::Error => "an invalid character",
            Token::Let => "`let`",
            Token::Param => "`param`",
            Token::In => "`in`",
            Token::Atlas => "`atlas`",
            Token::Material => "`material`",
            Token::Render => "`render`",
            Token::On => "`on`",
            Token::Seed => "`seed`",
            Token::Tangent => "`tangent`",
            Token::Merge => "`merge`",
            Token::True => "`true`",
            Token::False => "`false`",
            Token::Ident(s) => return write!(f, "identifier `{s}`"),
            Token::Number(s) | Token::BadNumber(s) => return write!(f, "number `{s}`"),
            Token::Str(_) | Token::UnterminatedStr(_) => "a string",
            Token::LineComment(_) | Token::BlockComment(_) => "a comment",
            Token::LParen => "`(`",
            Token::RParen => "`)`",
            Token::LBracket => "`[`",
            Token::RBracket => "`]`",
            Token::LBrace => "`{`",
            Token::RBrace => "`}`",
            Token::Comma => "`,`",
            Token::Semi => "`;`",
            Token::Colon => "`:`",
            Token::Dot => "`.`",
            Token::Assign => "`=`",
            Token::Plus => "`+`",
            Token::Minus => "`-`",
            Token::Star => "`*`",
            Token::Slash => "`/`",
            Token::Percent => "`%`",
            Token::Pipe => "`|`",
            Token::Amp => "`&`",
            Token::Bang => "`!`",
            Token::EqEq => "`==`",
            Token::NotEq => "`!=`",
            Token::Lt => "`<`",
            Token::Le => "`<=`",
            Token::Gt => "`>`",
            Token::Ge => "`>=`",
        };
        f.write_str(s)
    }
}

/// A comment kept for the formatter and for editor features.
#[derive(Debug, Clone, PartialEq)]
pub struct Comment {
    pub span: Span,
    pub block: bool,
}

/// The result of lexing a whole file.
#[derive(Debug, Clone)]
pub struct Lexed<'a> {
    /// Significant tokens, comments removed. Error tokens stay in so the parser sees them.
    pub tokens: Vec<(Token<'a>, Span)>,
    pub comments: Vec<Comment>,
}

/// Lexes a whole file. Never fails: problems become diagnostics.
pub fn lex<'a>(src: &'a str, diags: &mut Vec<Diagnostic>) -> Lexed<'a> {
    let mut tokens = Vec::new();
    let mut comments = Vec::new();
    let mut lexer = Token::lexer(src);
    // A UTF-8 byte-order mark (Windows editors write one) is not part of the text.
    if src.starts_with(super::source::BOM) {
        lexer.bump(super::source::BOM.len_utf8());
    }
    // Runs of invalid characters are reported once.
    let mut error_run: Option<Span> = None;
    let flush = |run: &mut Option<Span>, diags: &mut Vec<Diagnostic>| {
        if let Some(span) = run.take() {
            let text = &src[span.range()];
            let what = if text.chars().count() == 1 {
                format!(
                    "unexpected character {:?}",
                    text.chars().next().unwrap_or(' ')
                )
            } else {
                format!("unexpected characters {}", crate::diagnostic::quote(text))
            };
            diags.push(Diagnostic::error(
                codes::E_UNEXPECTED_CHAR,
                what,
                span,
                "not part of the language",
            ));
        }
    };
    while let Some(result) = lexer.next() {
        let span = Span::from(lexer.span());
        let tok = result.unwrap_or(Token::Error);
        if tok == Token::Error {
            error_run = Some(match error_run {
                Some(run) if run.end == span.start => run.to(span),
                Some(run) => {
                    flush(&mut Some(run), diags);
                    span
                }
                None => span,
            });
            tokens.push((tok, span));
            continue;
        }
        flush(&mut error_run, diags);
        match tok {
            Token::LineComment(_) => comments.push(Comment { span, block: false }),
            Token::BlockComment(closed) => {
                if !closed {
                    diags.push(
                        Diagnostic::error(
                            codes::E_UNTERMINATED_COMMENT,
                            "unterminated block comment",
                            Span::new(span.start, span.start + 2),
                            "this comment is never closed",
                        )
                        .with_help("close it with `*/`"),
                    );
                }
                comments.push(Comment { span, block: true });
            }
            Token::UnterminatedStr(_) => {
                diags.push(
                    Diagnostic::error(
                        codes::E_UNTERMINATED_STRING,
                        "unterminated string",
                        span,
                        "this string has no closing quote",
                    )
                    .with_help("strings end with `\"` on the same line"),
                );
                tokens.push((tok, span));
            }
            Token::BadNumber(text) => {
                diags.push(
                    Diagnostic::error(
                        codes::E_BAD_NUMBER,
                        format!("invalid number `{text}`"),
                        span,
                        "the exponent has no digits",
                    )
                    .with_help("write the exponent's digits, as in `1e-3`"),
                );
                tokens.push((tok, span));
            }
            _ => tokens.push((tok, span)),
        }
    }
    flush(&mut error_run, diags);
    Lexed { tokens, comments }
}

/// Decodes the escapes of a string token (with its quotes).
pub fn unescape(raw: &str) -> String {
    let inner = raw.strip_prefix('"').unwrap_or(raw);
    let inner = inner.strip_suffix('"').unwrap_or(inner);
    let mut out = String::with_capacity(inner.len());
    let mut chars = inner.chars();
    while let Some(c) = chars.next() {
        if c == '\\' {
            match chars.next() {
                Some('n') => out.push('\n'),
                Some('t') => out.push('\t'),
                Some(other) => out.push(other),
                None => {}
            }
        } else {
            out.push(c);
        }
    }
    out
}
