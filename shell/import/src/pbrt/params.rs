//! A directive's parameter list, `"type name" value` pairs, each marked
//! when the translation reads it so that the rest is refused by name.

use super::lexer::{Tok, Token};
use crate::error::{ImportError, Loc};
use std::cell::Cell;

/// One parameter.
#[derive(Debug)]
pub struct Param {
    /// `float`, `rgb`, `point3`, `string`, ...
    pub ty: String,
    /// Its name.
    pub name: String,
    /// Its values: numbers, strings or booleans, as written.
    pub values: Vec<Tok>,
    /// Where its declaration is.
    pub loc: Loc,
    used: Cell<bool>,
}

/// A directive's parameters.
#[derive(Debug, Default)]
pub struct Params {
    /// In order.
    pub list: Vec<Param>,
}

/// Read `"type name" value...` pairs from `toks[*i..]` while they last.
pub fn read(toks: &[Token], i: &mut usize) -> Result<Params, ImportError> {
    let mut out = Params::default();
    while let Some(Token {
        tok: Tok::Str(decl),
        loc,
    }) = toks.get(*i)
    {
        let mut words = decl.split_whitespace();
        let (Some(ty), Some(name), None) = (words.next(), words.next(), words.next()) else {
            // A bare string is a directive's own argument, not a parameter.
            break;
        };
        *i += 1;
        let values = match toks.get(*i).map(|t| &t.tok) {
            Some(Tok::Open) => {
                *i += 1;
                let mut v = Vec::new();
                loop {
                    match toks.get(*i) {
                        Some(Token {
                            tok: Tok::Close, ..
                        }) => {
                            *i += 1;
                            break;
                        }
                        Some(Token {
                            tok: t @ (Tok::Word(_) | Tok::Str(_)),
                            ..
                        }) => {
                            v.push(t.clone());
                            *i += 1;
                        }
                        _ => {
                            return Err(ImportError::invalid(
                                loc,
                                format!("\"{decl}\": its [ is not closed"),
                            ))
                        }
                    }
                }
                v
            }
            Some(t @ (Tok::Word(_) | Tok::Str(_))) => {
                *i += 1;
                vec![t.clone()]
            }
            _ => {
                return Err(ImportError::invalid(
                    loc,
                    format!("\"{decl}\" has no value"),
                ))
            }
        };
        if out.list.iter().any(|p| p.name == name) {
            return Err(ImportError::invalid(
                loc,
                format!("the parameter `{name}` is given twice"),
            ));
        }
        out.list.push(Param {
            ty: ty.to_string(),
            name: name.to_string(),
            values,
            loc: loc.clone(),
            used: Cell::new(false),
        });
    }
    Ok(out)
}

impl Params {
    /// The parameter `name`, marked read.
    pub fn get(&self, name: &str) -> Option<&Param> {
        let p = self.list.iter().find(|p| p.name == name)?;
        p.used.set(true);
        Some(p)
    }

    /// `name`'s numbers, checked against the types `types` and the count `n`.
    pub fn numbers(
        &self,
        name: &str,
        types: &[&str],
        n: usize,
    ) -> Result<Option<Vec<f64>>, ImportError> {
        let Some(p) = self.get(name) else {
            return Ok(None);
        };
        if !types.contains(&p.ty.as_str()) {
            return Err(ImportError::invalid(
                &p.loc,
                format!("`{name}` is a {}, expected {}", p.ty, types.join(" or ")),
            ));
        }
        let v = p
            .values
            .iter()
            .map(|t| match t {
                Tok::Word(w) => w.parse::<f64>().ok().filter(|x| x.is_finite()),
                _ => None,
            })
            .collect::<Option<Vec<f64>>>()
            .ok_or_else(|| {
                ImportError::invalid(&p.loc, format!("`{name}`: expected finite numbers"))
            })?;
        if v.len() != n {
            return Err(ImportError::invalid(
                &p.loc,
                format!("`{name}`: expected {n} numbers, found {}", v.len()),
            ));
        }
        Ok(Some(v))
    }

    /// One number, or `default`.
    pub fn float(&self, name: &str, default: f64) -> Result<f64, ImportError> {
        Ok(self
            .numbers(name, &["float", "integer"], 1)?
            .map_or(default, |v| v[0]))
    }

    /// Three numbers (a point, a vector, an RGB colour), or `default`.
    pub fn three(
        &self,
        name: &str,
        types: &[&str],
        default: [f64; 3],
    ) -> Result<[f64; 3], ImportError> {
        Ok(self
            .numbers(name, types, 3)?
            .map_or(default, |v| [v[0], v[1], v[2]]))
    }

    /// One string, or `default`.
    pub fn string(&self, name: &str, default: &str) -> Result<String, ImportError> {
        let Some(p) = self.get(name) else {
            return Ok(default.to_string());
        };
        match &p.values[..] {
            [Tok::Str(s)] if p.ty == "string" => Ok(s.clone()),
            _ => Err(ImportError::invalid(
                &p.loc,
                format!("`{name}`: expected one string"),
            )),
        }
    }

    /// One boolean, or `default`.
    pub fn bool(&self, name: &str, default: bool) -> Result<bool, ImportError> {
        let Some(p) = self.get(name) else {
            return Ok(default);
        };
        match &p.values[..] {
            [Tok::Word(w) | Tok::Str(w)] if p.ty == "bool" && (w == "true" || w == "false") => {
                Ok(w == "true")
            }
            _ => Err(ImportError::invalid(
                &p.loc,
                format!("`{name}`: expected true or false"),
            )),
        }
    }

    /// The parameters not read, for refusal.
    pub fn unread(&self) -> impl Iterator<Item = &Param> {
        self.list.iter().filter(|p| !p.used.get())
    }
}
