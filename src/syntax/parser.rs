//! The parser: tokens → AST, built on chumsky 0.13 with error recovery.
//!
//! The file is first split at the item keywords (`let`, `atlas`, `material`,
//! `render`), which can appear nowhere else, so a syntax error in one item never
//! hides the errors of another. Inside an item, chumsky recovers at statement
//! boundaries (`;`, `}`) and at balanced delimiters, so one run reports every
//! independent syntax error.

use super::ast::*;
use super::lexer::{lex, unescape, Comment, Token};
use super::reuse::ItemCache;
use crate::codes;
use crate::diagnostic::Diagnostic;
use crate::span::Span;
use chumsky::input::{Input as _, ValueInput};
use chumsky::pratt::*;
use chumsky::prelude::*;

/// How deep one expression may be: each bracket, prefix operator, binary operator and
/// method call (`.`) of a chain counts one level, since each nests the tree one level
/// deeper. Every later pass (checking, folding, lowering, evaluation, code generation,
/// formatting) recurses at most this deep on a file's own expressions; `let` bindings
/// are bounded after inlining by `sema::MAX_INLINED_DEPTH`.
pub const MAX_NESTING: usize = 256;

/// The result of parsing a file.
#[derive(Debug, Clone)]
pub struct Parsed {
    pub file: File,
    pub comments: Vec<Comment>,
}

/// Lexes and parses a whole file. Never fails and never panics: problems become diagnostics.
pub fn parse(src: &str, diags: &mut Vec<Diagnostic>) -> Parsed {
    parse_reusing(src, diags, None)
}

/// [`parse`], reusing the items of `cache` whose text is unchanged (and keeping this
/// parse's items in it for the next). The result is the same as [`parse`]'s.
pub fn parse_reusing(
    src: &str,
    diags: &mut Vec<Diagnostic>,
    mut cache: Option<&mut ItemCache>,
) -> Parsed {
    let lexed = lex(src, diags);
    // Invalid characters were reported by the lexer; the parser works around them.
    let tokens: Vec<(Token, SimpleSpan)> = lexed
        .tokens
        .iter()
        .filter(|(t, _)| *t != Token::Error)
        .map(|(t, s)| (*t, SimpleSpan::from(s.start..s.end)))
        .collect();
    // A syntax error at the token right after an invalid character repeats that error.
    let after_error: Vec<usize> = lexed
        .tokens
        .windows(2)
        .filter(|w| w[0].0 == Token::Error && w[1].0 != Token::Error)
        .map(|w| w[1].1.start)
        .collect();
    let mut item_diags = Vec::new();

    let mut items = Vec::new();
    let mut start = 0;
    // An item keyword used as a name (`x.material`, `paint(material: m)`) starts nothing.
    let starts_item = |i: usize| {
        tokens[i].0.starts_item()
            && !(i > 0 && tokens[i - 1].0 == Token::Dot)
            && tokens.get(i + 1).is_none_or(|(t, _)| *t != Token::Colon)
    };
    while start < tokens.len() {
        let mut end = start + 1;
        while end < tokens.len() && !starts_item(end) {
            end += 1;
        }
        let chunk = &tokens[start..end];
        let next = tokens.get(end).map(|(t, s)| (*t, to_span(*s)));
        let eoi = next.map(|(_, s)| s.start).unwrap_or(src.len());
        if !chunk[0].0.starts_item() {
            let span = to_span(chunk[0].1).to(to_span(chunk[chunk.len() - 1].1));
            diags.push(
                Diagnostic::error(
                    codes::E_SYNTAX,
                    format!("expected an item, found {}", chunk[0].0),
                    span,
                    "expected `let`, `atlas`, `material` or `render`",
                )
                .with_note(
                    "a scene file is a sequence of `let`, `atlas`, `material` and `render` items",
                ),
            );
        } else {
            let (at, last) = (chunk[0].1.start, chunk[chunk.len() - 1].1.end);
            let text = &src[at..last];
            match cache.as_deref_mut().and_then(|c| c.take(text, at)) {
                Some(item) => items.push(item),
                None => {
                    let before = item_diags.len();
                    if let Some(item) = parse_item(chunk, eoi, next, &mut item_diags) {
                        let clean = item_diags.len() == before
                            && !matches!(item.kind, ItemKind::Error { .. });
                        if let Some(c) = cache.as_deref_mut().filter(|_| clean) {
                            c.keep(text, at, &item);
                        }
                        items.push(item);
                    }
                }
            }
        }
        start = end;
    }
    if let Some(c) = cache {
        c.finish();
    }
    diags.extend(item_diags.into_iter().filter(|d| {
        !(d.code == codes::E_SYNTAX && d.span().is_some_and(|s| after_error.contains(&s.start)))
    }));
    Parsed {
        file: File { items },
        comments: lexed.comments,
    }
}

fn to_span(s: SimpleSpan) -> Span {
    Span::new(s.start, s.end)
}

fn chunk_span(chunk: &[(Token, SimpleSpan)]) -> Span {
    to_span(chunk[0].1).to(to_span(chunk[chunk.len() - 1].1))
}

/// The name an item would define, read straight off its tokens, for items that fail to parse.
fn fallback_name(chunk: &[(Token, SimpleSpan)]) -> Option<Ident> {
    match (chunk.first(), chunk.get(1)) {
        (
            Some((Token::Let | Token::Param | Token::Atlas | Token::Material, _)),
            Some((Token::Ident(n), s)),
        ) => Some(Ident {
            name: n.to_string(),
            span: to_span(*s),
        }),
        _ => None,
    }
}

/// Reports nesting deeper than [`MAX_NESTING`]; returns false if the item must not be parsed.
fn check_nesting(chunk: &[(Token, SimpleSpan)], diags: &mut Vec<Diagnostic>) -> bool {
    // Chain links (binary operators, `.`) counted per bracket level, and the brackets.
    let mut links: Vec<usize> = vec![0];
    let mut total_links = 0usize;
    let mut prefix_run = 0usize;
    let mut prev: Option<Token> = None;
    for (tok, span) in chunk {
        let after_operand = matches!(
            prev,
            Some(
                Token::Ident(_)
                    | Token::Number(_)
                    | Token::RParen
                    | Token::RBracket
                    | Token::True
                    | Token::False
                    | Token::Str(_)
            )
        );
        let is_prefix = matches!(tok, Token::Minus | Token::Bang) && !after_operand;
        let is_link = !is_prefix && (*tok == Token::Dot || tok.is_binary_operator());
        match tok {
            Token::LParen | Token::LBracket | Token::LBrace => links.push(0),
            Token::RParen | Token::RBracket | Token::RBrace if links.len() > 1 => {
                total_links -= links.pop().unwrap_or(0);
            }
            // A statement ends every chain of its level.
            Token::Semi | Token::Comma => {
                if let Some(l) = links.last_mut() {
                    total_links -= *l;
                    *l = 0;
                }
            }
            _ if is_link => {
                if let Some(l) = links.last_mut() {
                    *l += 1;
                    total_links += 1;
                }
            }
            _ => {}
        }
        prefix_run = if is_prefix { prefix_run + 1 } else { 0 };
        let depth = links.len() - 1 + total_links + prefix_run;
        if depth > MAX_NESTING {
            diags.push(
                Diagnostic::error(
                    codes::E_TOO_DEEP,
                    format!("expression nested deeper than {MAX_NESTING} levels"),
                    to_span(*span),
                    format!("nesting level {} starts here", MAX_NESTING + 1),
                )
                .with_note(format!(
                    "brackets, operators and method calls may nest at most {MAX_NESTING} \
                     levels: each link of a chain such as `a | b | c` or \
                     `s.translate(…).rotate_x(…)` counts one"
                ))
                .with_help("split the expression with `let` bindings"),
            );
            return false;
        }
        prev = Some(*tok);
    }
    true
}

fn parse_item(
    chunk: &[(Token, SimpleSpan)],
    eoi: usize,
    next: Option<(Token, Span)>,
    diags: &mut Vec<Diagnostic>,
) -> Option<Item> {
    let span = chunk_span(chunk);
    if !check_nesting(chunk, diags) {
        return Some(Item {
            kind: ItemKind::Error {
                name: fallback_name(chunk),
            },
            span,
        });
    }
    let input = chunk.map(SimpleSpan::from(eoi..eoi), |(t, s)| (t, s));
    let (output, errors) = item_parser()
        .then(trailing())
        .parse(input)
        .into_output_errors();
    // An unterminated string swallows the rest of its line; what the parser says after it
    // only repeats the lexer's error.
    let swallowed = chunk
        .iter()
        .find(|(t, _)| matches!(t, Token::UnterminatedStr(_)))
        .map(|(_, s)| s.start);
    for e in errors {
        if swallowed.is_some_and(|at| e.span().start >= at) {
            continue;
        }
        diags.push(syntax_error(&e, next));
    }
    match output {
        Some((item, trailing)) => {
            if let Some(extra) = trailing {
                diags.push(
                    Diagnostic::error(
                        codes::E_SYNTAX,
                        "unexpected tokens after the end of the item",
                        extra,
                        "expected `let`, `atlas`, `material` or `render`",
                    )
                    .with_help("each item ends with `;` or with its closing `}`"),
                );
            }
            Some(item)
        }
        None => Some(Item {
            kind: ItemKind::Error {
                name: fallback_name(chunk),
            },
            span,
        }),
    }
}

fn syntax_error(e: &Rich<'_, Token<'_>, SimpleSpan>, next: Option<(Token, Span)>) -> Diagnostic {
    let mut expected: Vec<String> = e.expected().map(|p| pattern_text(p)).collect();
    expected.sort();
    expected.dedup();
    // Operators can always continue an expression; listing them buries what is missing.
    let structural = ["`)`", "`]`", "`}`", "`;`", "`,`", "`{`", "`=`", "`on`"];
    if expected.iter().any(|x| structural.contains(&x.as_str())) {
        expected.retain(|x| {
            structural.contains(&x.as_str()) || !x.starts_with('`') && x != "something else"
        });
        expected.retain(|x| x != "something else");
    } else if expected.iter().any(|x| x == "an expression") {
        expected = vec![String::from("an expression")];
    }
    let expected_text = match expected.len() {
        0 => String::from("something else"),
        1 => expected[0].clone(),
        n => format!("{} or {}", expected[..n - 1].join(", "), expected[n - 1]),
    };
    let (found, span) = match e.found() {
        Some(tok) => (tok.to_string(), to_span(*e.span())),
        None => match next {
            Some((tok, s)) => (tok.to_string(), Span::new(s.start, s.end)),
            None => (String::from("end of file"), to_span(*e.span())),
        },
    };
    let is_custom = matches!(e.reason(), chumsky::error::RichReason::Custom(_));
    if is_custom {
        return Diagnostic::error(codes::E_SYNTAX, e.reason().to_string(), span, "here");
    }
    let mut d = Diagnostic::error(
        codes::E_SYNTAX,
        format!("expected {expected_text}, found {found}"),
        span,
        format!("expected {expected_text}"),
    );
    if let Some(ctx) = e.contexts().last() {
        d = d.with_label(to_span(*ctx.1), format!("while parsing this {}", ctx.0));
    }
    if found == "`}`" && expected.iter().any(|x| x == "`;`") || expected == ["`;`"] {
        d = d.with_help("statements end with `;`");
    }
    d
}

fn pattern_text(p: &chumsky::error::RichPattern<'_, Token<'_>>) -> String {
    use chumsky::error::RichPattern;
    match p {
        RichPattern::Token(t) => t.to_string(),
        RichPattern::Label(l) if l.as_ref() == "expression" => String::from("an expression"),
        RichPattern::Label(l) => l.to_string(),
        RichPattern::EndOfInput => String::from("end of item"),
        RichPattern::SomethingElse => String::from("something else"),
        RichPattern::Any => String::from("any token"),
        other => other.to_string(),
    }
}

type Extra<'t, 'a> = extra::Err<Rich<'t, Token<'a>, SimpleSpan>>;

/// Whatever follows a complete item inside its chunk: an error to report.
fn trailing<'t, 'a: 't, I>() -> impl Parser<'t, I, Option<Span>, Extra<'t, 'a>> + Clone
where
    I: ValueInput<'t, Token = Token<'a>, Span = SimpleSpan>,
{
    any()
        .repeated()
        .at_least(1)
        .to_span()
        .map(|s: SimpleSpan| to_span(s))
        .or_not()
}

/// A name after `.` or before `:` in a call: an identifier, or a keyword, since
/// members and parameters may be named like one (`skin.seed`, `paint(material: m)`).
fn member<'t, 'a: 't, I>() -> impl Parser<'t, I, Ident, Extra<'t, 'a>> + Clone
where
    I: ValueInput<'t, Token = Token<'a>, Span = SimpleSpan>,
{
    select! {
        Token::Ident(n) => n,
        Token::Let => "let",
        Token::Param => "param",
        Token::In => "in",
        Token::Atlas => "atlas",
        Token::Material => "material",
        Token::Render => "render",
        Token::On => "on",
        Token::Seed => "seed",
        Token::Tangent => "tangent",
        Token::Merge => "merge",
    }
    .map_with(|n: &str, e| Ident {
        name: n.to_string(),
        span: to_span(e.span()),
    })
    .labelled("a name")
}

fn ident<'t, 'a: 't, I>() -> impl Parser<'t, I, Ident, Extra<'t, 'a>> + Clone
where
    I: ValueInput<'t, Token = Token<'a>, Span = SimpleSpan>,
{
    select! { Token::Ident(n) => n }
        .map_with(|n: &str, e| Ident {
            name: n.to_string(),
            span: to_span(e.span()),
        })
        .labelled("a name")
}

/// Skips a broken statement: up to and including its `;`, or up to the block's `}`.
fn skip_statement<'t, 'a: 't, I>() -> impl Parser<'t, I, (), Extra<'t, 'a>> + Clone
where
    I: ValueInput<'t, Token = Token<'a>, Span = SimpleSpan>,
{
    let body = none_of([Token::Semi, Token::RBrace]).repeated();
    body.then(just(Token::Semi))
        .ignored()
        .or(body.at_least(1).ignored())
}

/// `{ stmt* }`; a missing `}` is reported and the block still counts.
fn block<'t, 'a: 't, I, O>(
    stmt: impl Parser<'t, I, O, Extra<'t, 'a>> + Clone,
) -> impl Parser<'t, I, Vec<O>, Extra<'t, 'a>> + Clone
where
    I: ValueInput<'t, Token = Token<'a>, Span = SimpleSpan>,
{
    let close_brace = just(Token::RBrace)
        .ignored()
        .recover_with(via_parser(empty()));
    stmt.repeated()
        .collect::<Vec<_>>()
        .delimited_by(just(Token::LBrace), close_brace)
        .labelled("block")
}

fn number(text: &str) -> ExprKind {
    let (digits, unit) = if let Some(d) = text.strip_suffix("deg") {
        (d, Some(Unit::Deg))
    } else if let Some(d) = text.strip_suffix("rad") {
        (d, Some(Unit::Rad))
    } else {
        (text, None)
    };
    match digits.parse::<f64>() {
        Ok(value) => ExprKind::Number { value, unit },
        Err(_) => ExprKind::Error,
    }
}

pub(crate) fn expr_parser<'t, 'a: 't, I>() -> impl Parser<'t, I, Expr, Extra<'t, 'a>> + Clone
where
    I: ValueInput<'t, Token = Token<'a>, Span = SimpleSpan>,
{
    recursive(|expr| {
        let arg = member()
            .then_ignore(just(Token::Colon))
            .then(expr.clone())
            .map(|(name, value)| Arg {
                name: Some(name),
                value,
            })
            .or(expr.clone().map(|value| Arg { name: None, value }));
        let args = arg
            .separated_by(just(Token::Comma))
            .allow_trailing()
            .collect::<Vec<_>>()
            .delimited_by(just(Token::LParen), just(Token::RParen))
            .labelled("arguments");

        let atom = atom(expr, args.clone());
        let postfix = atom.foldl_with(
            just(Token::Dot)
                .ignore_then(member())
                .then(args.or_not())
                .repeated(),
            |receiver, (name, args), e| {
                let span = to_span(e.span());
                match args {
                    Some(args) => Expr::new(
                        ExprKind::Method {
                            receiver: Box::new(receiver),
                            method: name,
                            args,
                        },
                        span,
                    ),
                    None => Expr::new(
                        ExprKind::Field {
                            receiver: Box::new(receiver),
                            field: name,
                        },
                        span,
                    ),
                }
            },
        );
        operators(postfix).labelled("expression")
    })
}

/// An operand: a literal, a call or a name, a vector or a parenthesised expression
/// (`expr`), recovering from broken brackets as an error expression.
fn atom<'t, 'a: 't, I, E, A>(expr: E, args: A) -> impl Parser<'t, I, Expr, Extra<'t, 'a>> + Clone
where
    I: ValueInput<'t, Token = Token<'a>, Span = SimpleSpan>,
    E: Parser<'t, I, Expr, Extra<'t, 'a>> + Clone + 't,
    A: Parser<'t, I, Vec<Arg>, Extra<'t, 'a>> + Clone + 't,
{
    let literal = select! {
        Token::Number(t) => number(t),
        Token::BadNumber(_) => ExprKind::Error,
        Token::True => ExprKind::Bool(true),
        Token::False => ExprKind::Bool(false),
        Token::Str(s) => ExprKind::Str(unescape(s)),
        Token::UnterminatedStr(s) => ExprKind::Str(unescape(s)),
    }
    .map_with(|k, e| Expr::new(k, to_span(e.span())));

    let call_or_name = ident()
        .then(args.clone().or_not())
        .map_with(|(name, args), e| {
            let span = to_span(e.span());
            match args {
                Some(args) => Expr::new(ExprKind::Call { callee: name, args }, span),
                None => Expr::new(ExprKind::Name(name.name), span),
            }
        });

    let vector = expr
        .clone()
        .separated_by(just(Token::Comma))
        .allow_trailing()
        .collect::<Vec<_>>()
        .delimited_by(just(Token::LBracket), just(Token::RBracket))
        .map_with(|items, e| Expr::new(ExprKind::Vector(items), to_span(e.span())))
        .labelled("vector");

    let paren = expr
        .clone()
        .delimited_by(just(Token::LParen), just(Token::RParen))
        .map_with(|inner, e| Expr::new(ExprKind::Paren(Box::new(inner)), to_span(e.span())));

    literal
        .or(call_or_name)
        .or(vector)
        .or(paren)
        .recover_with(via_parser(nested_delimiters(
            Token::LParen,
            Token::RParen,
            [
                (Token::LBracket, Token::RBracket),
                (Token::LBrace, Token::RBrace),
            ],
            |s| Expr::new(ExprKind::Error, to_span(s)),
        )))
        .recover_with(via_parser(nested_delimiters(
            Token::LBracket,
            Token::RBracket,
            [
                (Token::LParen, Token::RParen),
                (Token::LBrace, Token::RBrace),
            ],
            |s| Expr::new(ExprKind::Error, to_span(s)),
        )))
        .labelled("expression")
        .boxed()
}

/// The operators over `operand`, by precedence from the highest: unary `-` and `!`;
/// `*`, `/`, `%`; `+`, `-`; the comparisons; `&`; `|` (binary ones associate left).
fn operators<'t, 'a: 't, I, O>(operand: O) -> impl Parser<'t, I, Expr, Extra<'t, 'a>> + Clone
where
    I: ValueInput<'t, Token = Token<'a>, Span = SimpleSpan>,
    O: Parser<'t, I, Expr, Extra<'t, 'a>> + Clone,
{
    let bin = |l: Expr, op: BinaryOp, r: Expr| {
        let span = l.span.to(r.span);
        Expr::new(
            ExprKind::Binary {
                op,
                lhs: Box::new(l),
                rhs: Box::new(r),
            },
            span,
        )
    };
    let un = |op: (UnaryOp, Span), r: Expr| {
        let span = op.1.to(r.span);
        Expr::new(
            ExprKind::Unary {
                op: op.0,
                expr: Box::new(r),
            },
            span,
        )
    };
    let unop = |t: Token<'a>, op: UnaryOp| just(t).map_with(move |_, e| (op, to_span(e.span())));
    operand.pratt((
        prefix(7, unop(Token::Minus, UnaryOp::Neg), move |op, r, _| {
            un(op, r)
        }),
        prefix(7, unop(Token::Bang, UnaryOp::Not), move |op, r, _| {
            un(op, r)
        }),
        infix(
            left(6),
            just(Token::Star).to(BinaryOp::Mul),
            move |l, op, r, _| bin(l, op, r),
        ),
        infix(
            left(6),
            just(Token::Slash).to(BinaryOp::Div),
            move |l, op, r, _| bin(l, op, r),
        ),
        infix(
            left(6),
            just(Token::Percent).to(BinaryOp::Rem),
            move |l, op, r, _| bin(l, op, r),
        ),
        infix(
            left(5),
            just(Token::Plus).to(BinaryOp::Add),
            move |l, op, r, _| bin(l, op, r),
        ),
        infix(
            left(5),
            just(Token::Minus).to(BinaryOp::Sub),
            move |l, op, r, _| bin(l, op, r),
        ),
        infix(
            left(4),
            select! {
                Token::EqEq => BinaryOp::Eq,
                Token::NotEq => BinaryOp::Ne,
                Token::Lt => BinaryOp::Lt,
                Token::Le => BinaryOp::Le,
                Token::Gt => BinaryOp::Gt,
                Token::Ge => BinaryOp::Ge,
            },
            move |l, op, r, _| bin(l, op, r),
        ),
        infix(
            left(3),
            just(Token::Amp).to(BinaryOp::And),
            move |l, op, r, _| bin(l, op, r),
        ),
        infix(
            left(2),
            just(Token::Pipe).to(BinaryOp::Or),
            move |l, op, r, _| bin(l, op, r),
        ),
    ))
}

fn item_parser<'t, 'a: 't, I>() -> impl Parser<'t, I, Item, Extra<'t, 'a>> + Clone
where
    I: ValueInput<'t, Token = Token<'a>, Span = SimpleSpan>,
{
    let expr = expr_parser().boxed();
    // An expression ending a statement; when it is broken, the rest of the statement is skipped.
    let expr_semi = expr
        .clone()
        .then_ignore(just(Token::Semi))
        .recover_with(via_parser(
            skip_statement().map_with(|_, e| Expr::new(ExprKind::Error, to_span(e.span()))),
        ));

    let setting = ident()
        .then_ignore(just(Token::Assign))
        .then(expr_semi.clone())
        .map_with(|(name, value), e| Setting {
            name,
            value,
            span: to_span(e.span()),
        });

    let seed = just(Token::Seed)
        .ignore_then(ident())
        .then_ignore(just(Token::Assign))
        .then(expr.clone())
        .then(just(Token::Tangent).ignore_then(expr.clone()).or_not())
        .then_ignore(just(Token::Semi))
        .map_with(|((name, position), tangent), e| AtlasStmt::Seed {
            name,
            position,
            tangent,
            span: to_span(e.span()),
        });
    let merge = just(Token::Merge)
        .ignore_then(ident().repeated().at_least(1).collect::<Vec<_>>())
        .then_ignore(just(Token::Semi))
        .map_with(|seeds, e| AtlasStmt::Merge {
            seeds,
            span: to_span(e.span()),
        });
    let atlas_stmt = seed
        .or(merge)
        .or(setting.clone().map(AtlasStmt::Setting))
        .recover_with(via_parser(
            skip_statement().map_with(|_, e| AtlasStmt::Error(to_span(e.span()))),
        ))
        .boxed();
    let setting_stmt = setting
        .clone()
        .map(Some)
        .recover_with(via_parser(skip_statement().to(None)))
        .boxed();
    let settings_block = block(setting_stmt)
        .map(|v: Vec<Option<Setting>>| v.into_iter().flatten().collect::<Vec<_>>());

    let let_item = just(Token::Let)
        .ignore_then(ident())
        .then_ignore(just(Token::Assign))
        .then(expr_semi)
        .map(|(name, value)| ItemKind::Let { name, value });
    let param_item = just(Token::Param)
        .ignore_then(ident())
        .then_ignore(just(Token::Assign))
        .then(expr.clone())
        .then(just(Token::In).ignore_then(expr.clone()).or_not())
        .then_ignore(just(Token::Semi))
        .map(|((name, value), range)| ItemKind::Param { name, value, range });
    let atlas_item = just(Token::Atlas)
        .ignore_then(ident())
        .then_ignore(just(Token::On))
        .then(expr.clone())
        .then(block(atlas_stmt))
        .map(|((name, shape), body)| ItemKind::Atlas { name, shape, body });
    let material_item = just(Token::Material)
        .ignore_then(ident())
        .then(settings_block.clone())
        .map(|(name, body)| ItemKind::Material { name, body });
    let render_item = just(Token::Render)
        .ignore_then(expr)
        .then(settings_block.or(just(Token::Semi).to(Vec::new())))
        .map(|(target, body)| ItemKind::Render { target, body });

    let_item
        .or(param_item)
        .or(atlas_item)
        .or(material_item)
        .or(render_item)
        .map_with(|kind, e| Item {
            kind,
            span: to_span(e.span()),
        })
}
