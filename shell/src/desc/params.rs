//! Scene parameters: a `[params]` table of named values, used anywhere in
//! the scene as the string `"$name"` and set from the command line with
//! `--set params.name=value`. They are what Mitsuba's `<default>` and
//! `$name` become on import (`rtk import`), so that a scene keeps the knobs
//! its author gave it.
//!
//! A reference is a whole string value, `$` followed by a name of letters,
//! digits and `_` (not starting with a digit); it takes the parameter's
//! value, of any type (a number, an array, a table). `$$` at the start
//! escapes a literal `$`. A reference to an undefined parameter is an
//! error at the reference; `[params]` values do not refer to each other
//! (one pass, so no cycles).

use crate::error::{ErrorKind, SceneError};
use crate::tree::{Node, Origin, Val};

/// The parameter section's name.
pub const SECTION: &str = "params";

/// `root` with `[params]` removed and each `"$name"` replaced by its value
/// (a copy: the file's own tree keeps what was written, for messages).
pub fn substituted(root: &Node) -> Result<Node, SceneError> {
    let params: Vec<(String, Origin, Node)> = match root.get(SECTION).map(|n| &n.value) {
        None => Vec::new(),
        Some(Val::Table(t)) => t.clone(),
        Some(v) => {
            return Err(SceneError::invalid(
                &root.locate_origin(SECTION),
                SECTION,
                "",
                format!(
                    "[params] is a table of named values, found {}",
                    v.type_name()
                ),
            ))
        }
    };
    for (name, origin, _) in &params {
        if !is_name(name) {
            return Err(SceneError::invalid(
                origin,
                SECTION,
                name,
                "a parameter's name is letters, digits and `_`, not starting with a digit",
            ));
        }
    }
    let mut out = root.clone();
    if let Val::Table(t) = &mut out.value {
        t.retain(|(k, _, _)| k != SECTION);
    }
    replace(&mut out, &params, "")?;
    Ok(out)
}

/// Replace the references inside `node` (at key path `path`).
fn replace(
    node: &mut Node,
    params: &[(String, Origin, Node)],
    path: &str,
) -> Result<(), SceneError> {
    match &mut node.value {
        Val::Str(s) if s.starts_with("$$") => {
            s.remove(0);
        }
        Val::Str(s) if s.starts_with('$') => {
            let name = &s[1..];
            let Some((_, _, value)) = params.iter().find(|(k, _, _)| k == name) else {
                let defined: Vec<&str> = params.iter().map(|p| p.0.as_str()).collect();
                let (object, key) = path.rsplit_once('.').unwrap_or(("", path));
                return Err(SceneError::new(
                    ErrorKind::UnknownReference,
                    &node.origin,
                    object,
                    key,
                    format!("`{s}` names no scene parameter (write `$${name}` for a literal `$`)"),
                )
                .note(format!(
                    "[params] defines: {}",
                    if defined.is_empty() {
                        "nothing".to_string()
                    } else {
                        defined.join(", ")
                    }
                )));
            };
            node.value = value.value.clone();
        }
        Val::Arr(items) => {
            for n in items {
                replace(n, params, path)?;
            }
        }
        Val::Table(t) => {
            for (k, _, n) in t {
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                replace(n, params, &p)?;
            }
        }
        _ => {}
    }
    Ok(())
}

/// Letters, digits and `_`, not starting with a digit.
pub fn is_name(s: &str) -> bool {
    let mut c = s.chars();
    c.next()
        .is_some_and(|f| f.is_ascii_alphabetic() || f == '_')
        && c.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(src: &str) -> Node {
        crate::tree::parse(src).unwrap()
    }

    #[test]
    fn references_take_their_values_of_any_type() {
        let root = parse(
            "[params]\nspp = 32\ncolour = [0.1, 0.2, 0.3]\n[render]\nspp = \"$spp\"\n[shaders.a]\nalbedo = \"$colour\"\nname = \"$$spp\"\n",
        );
        let out = substituted(&root).unwrap();
        assert!(out.get(SECTION).is_none());
        let r = out.get("render").unwrap().get("spp").unwrap();
        assert!(matches!(r.value, Val::Int(32)));
        let a = out.get("shaders").unwrap().get("a").unwrap();
        assert!(matches!(&a.get("albedo").unwrap().value, Val::Arr(v) if v.len() == 3));
        assert!(matches!(&a.get("name").unwrap().value, Val::Str(s) if s == "$spp"));
    }

    #[test]
    fn an_undefined_reference_is_an_error_at_the_reference() {
        let root = parse("[params]\nspp = 32\n[render]\nspp = \"$sp\"\n");
        let e = substituted(&root).unwrap_err().to_string();
        assert!(e.contains("`$sp` names no scene parameter"), "{e}");
        assert!(e.contains("[params] defines: spp"), "{e}");
        let root = parse("[params]\n\"2x\" = 1\n");
        assert!(substituted(&root).is_err());
    }
}
