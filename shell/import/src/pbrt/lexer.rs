//! pbrt-v4's scene text as tokens: directive names and other bare words,
//! numbers, quoted strings and brackets, `#` comments skipped — the
//! grammar of pbrt-v4's `src/pbrt/parser.cpp` (its file format page:
//! "an identifier, then its parameter list").

use crate::error::{ImportError, Loc};
use std::path::PathBuf;
use std::sync::Arc;

/// A token.
#[derive(Debug, Clone, PartialEq)]
pub enum Tok {
    /// A bare word: a directive (`Shape`), `true`/`false`, or a number.
    Word(String),
    /// A quoted string, escapes resolved.
    Str(String),
    /// `[`.
    Open,
    /// `]`.
    Close,
}

/// A token and where it starts.
#[derive(Debug, Clone)]
pub struct Token {
    /// The token.
    pub tok: Tok,
    /// Where it starts.
    pub loc: Loc,
}

/// The tokens of `text` (the file `path`).
pub fn tokens(path: &Arc<PathBuf>, text: &str) -> Result<Vec<Token>, ImportError> {
    let mut out = Vec::new();
    let (mut line, mut col) = (1u32, 1u32);
    let mut it = text.chars().peekable();
    let at = |line, col| Loc {
        file: path.clone(),
        line,
        col,
    };
    while let Some(&c) = it.peek() {
        let start = at(line, col);
        let mut step = |it: &mut std::iter::Peekable<std::str::Chars>| {
            let c = it.next();
            if c == Some('\n') {
                line += 1;
                col = 1;
            } else {
                col += 1;
            }
            c
        };
        match c {
            c if c.is_whitespace() => {
                step(&mut it);
            }
            '#' => {
                while it.peek().is_some_and(|&c| c != '\n') {
                    step(&mut it);
                }
            }
            '[' | ']' => {
                step(&mut it);
                let tok = if c == '[' { Tok::Open } else { Tok::Close };
                out.push(Token { tok, loc: start });
            }
            '"' => {
                step(&mut it);
                let mut s = String::new();
                loop {
                    match step(&mut it) {
                        None | Some('\n') => {
                            return Err(ImportError::invalid(
                                &start,
                                "a string is not closed on its line",
                            ))
                        }
                        Some('"') => break,
                        Some('\\') => match step(&mut it) {
                            Some('n') => s.push('\n'),
                            Some('t') => s.push('\t'),
                            Some(e @ ('\\' | '"' | '\'')) => s.push(e),
                            other => {
                                return Err(ImportError::invalid(
                                    &start,
                                    format!(
                                        "the escape \\{} is not one pbrt reads",
                                        other.map(String::from).unwrap_or_default()
                                    ),
                                ))
                            }
                        },
                        Some(c) => s.push(c),
                    }
                }
                out.push(Token {
                    tok: Tok::Str(s),
                    loc: start,
                });
            }
            _ => {
                let mut s = String::new();
                while let Some(&c) = it.peek() {
                    if c.is_whitespace() || matches!(c, '"' | '[' | ']' | '#') {
                        break;
                    }
                    s.push(c);
                    step(&mut it);
                }
                out.push(Token {
                    tok: Tok::Word(s),
                    loc: start,
                });
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_keep_their_positions() {
        let p = Arc::new(PathBuf::from("s.pbrt"));
        let t = tokens(
            &p,
            "Shape \"sphere\" # a ball\n  \"float radius\" [ 2.5 ]\n",
        )
        .unwrap();
        let kinds: Vec<_> = t.iter().map(|t| t.tok.clone()).collect();
        assert_eq!(
            kinds,
            vec![
                Tok::Word("Shape".into()),
                Tok::Str("sphere".into()),
                Tok::Str("float radius".into()),
                Tok::Open,
                Tok::Word("2.5".into()),
                Tok::Close
            ]
        );
        assert_eq!((t[2].loc.line, t[2].loc.col), (2, 3));
        assert!(tokens(&p, "Shape \"sphere").is_err());
    }
}
