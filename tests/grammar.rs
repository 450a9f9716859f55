//! The editor grammar files agree with the lexer.

use sdfc::syntax::lexer::KEYWORDS;
use std::collections::BTreeSet;
use std::path::Path;

fn read_json(name: &str) -> serde_json::Value {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("grammar")
        .join(name);
    serde_json::from_str(&std::fs::read_to_string(&path).unwrap())
        .unwrap_or_else(|e| panic!("{name} is not valid JSON: {e}"))
}

#[test]
fn textmate_keywords_match_the_lexer() {
    let grammar = read_json("sdf.tmLanguage.json");
    assert_eq!(grammar["scopeName"], "source.sdf");
    let pattern = grammar["repository"]["keywords"]["match"]
        .as_str()
        .expect("repository.keywords.match");
    let inner = pattern
        .strip_prefix("\\b(")
        .and_then(|p| p.strip_suffix(")\\b"))
        .expect("keywords pattern has the form \\b(a|b|…)\\b");
    let textmate: BTreeSet<&str> = inner.split('|').collect();
    let lexer: BTreeSet<&str> = KEYWORDS.iter().copied().collect();
    assert_eq!(textmate, lexer);
}

#[test]
fn every_keyword_lexes_as_a_keyword() {
    use logos::Logos;
    use sdfc::syntax::lexer::Token;
    for kw in KEYWORDS {
        let tokens: Vec<_> = Token::lexer(kw).collect();
        assert_eq!(tokens.len(), 1, "{kw}");
        assert!(
            !matches!(tokens[0], Ok(Token::Ident(_)) | Err(_)),
            "`{kw}` lexes as {:?}",
            tokens[0]
        );
    }
}

#[test]
fn language_configuration_matches_the_comment_syntax() {
    let config = read_json("language-configuration.json");
    assert_eq!(config["comments"]["lineComment"], "//");
    assert_eq!(config["comments"]["blockComment"][0], "/*");
    assert_eq!(config["comments"]["blockComment"][1], "*/");
}

/// The VS Code extension's manifest points at the grammar files and runs `sdfc lsp`.
#[test]
fn vscode_extension_uses_the_grammar_files() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("editors/vscode");
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("package.json")).unwrap()).unwrap();
    let contributes = &manifest["contributes"];
    let config = contributes["languages"][0]["configuration"]
        .as_str()
        .unwrap();
    let grammar = contributes["grammars"][0]["path"].as_str().unwrap();
    assert_eq!(contributes["languages"][0]["extensions"][0], ".sdf");
    assert_eq!(
        contributes["grammars"][0]["scopeName"],
        read_json("sdf.tmLanguage.json")["scopeName"]
    );
    for path in [config, grammar] {
        let resolved = dir.join(path).canonicalize().unwrap();
        assert_eq!(
            resolved.parent().unwrap().file_name().unwrap(),
            "grammar",
            "{path}"
        );
    }
    let main = manifest["main"].as_str().unwrap();
    let script = std::fs::read_to_string(dir.join(main)).unwrap();
    assert!(script.contains("args: [\"lsp\"]"), "{script}");
    assert!(script.contains("vscode-languageclient"));
}
