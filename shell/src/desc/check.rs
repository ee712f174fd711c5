//! Typed reads of tree values, each error naming the object and the key.

use crate::error::SceneError;
use crate::tree::{Node, Origin, Val};

/// Largest coordinate, translation, scale or radiance the shell accepts:
/// the kernel's [`MAX_COORDINATE`](rtk_kernel::params::MAX_COORDINATE), in
/// f64 (beyond it f32 intersection loses all precision).
pub(crate) const MAX_COORDINATE: f64 = 1e12;

/// The entries of a table.
pub(crate) fn table<'n>(
    n: &'n Node,
    object: &str,
    key: &str,
) -> Result<&'n [(String, Origin, Node)], SceneError> {
    match &n.value {
        Val::Table(t) => Ok(t),
        v => Err(SceneError::invalid(
            &n.origin,
            object,
            key,
            format!("expected a table, found {}", v.type_name()),
        )),
    }
}

/// A string.
pub(crate) fn string(n: &Node, object: &str, key: &str) -> Result<String, SceneError> {
    match &n.value {
        Val::Str(s) => Ok(s.clone()),
        v => Err(SceneError::invalid(
            &n.origin,
            object,
            key,
            format!("expected a string, found {}", v.type_name()),
        )),
    }
}

/// An integer in `min..=max`.
pub(crate) fn integer(
    n: &Node,
    object: &str,
    key: &str,
    min: i64,
    max: i64,
) -> Result<i64, SceneError> {
    match &n.value {
        Val::Int(i) if (min..=max).contains(i) => Ok(*i),
        Val::Int(i) => Err(SceneError::invalid(
            &n.origin,
            object,
            key,
            format!("must be between {min} and {max}, got {i}"),
        )),
        v => Err(SceneError::invalid(
            &n.origin,
            object,
            key,
            format!("expected an integer, found {}", v.type_name()),
        )),
    }
}

/// A finite number (integer or float).
pub(crate) fn number(n: &Node, object: &str, key: &str) -> Result<f64, SceneError> {
    let v = match &n.value {
        Val::Int(i) => *i as f64,
        Val::Float(f) => *f,
        v => {
            return Err(SceneError::invalid(
                &n.origin,
                object,
                key,
                format!("expected a number, found {}", v.type_name()),
            ))
        }
    };
    if !v.is_finite() {
        return Err(SceneError::invalid(
            &n.origin,
            object,
            key,
            format!("must be a finite number, got {v}"),
        ));
    }
    Ok(v)
}

/// Refuse keys of a table outside `allowed`, pointing at the key.
pub(crate) fn unknown_keys(n: &Node, object: &str, allowed: &[&str]) -> Result<(), SceneError> {
    for (k, ko, _) in table(n, object, "")? {
        if !allowed.contains(&k.as_str()) {
            return Err(SceneError::invalid(
                ko,
                object,
                k,
                format!("unknown key; expected one of: {}", allowed.join(", ")),
            ));
        }
    }
    Ok(())
}

/// A value as JSON for a plugin. NaN and infinities are refused, and so are
/// numbers beyond f32's range: plugins read numbers as f32, where `1e39`
/// would arrive as infinity and be refused in words that no longer match
/// what the scene says.
pub(crate) fn json(n: &Node, object: &str, key: &str) -> Result<serde_json::Value, SceneError> {
    use serde_json::Value as J;
    Ok(match &n.value {
        Val::Str(s) => J::String(s.clone()),
        Val::Int(i) => J::from(*i),
        Val::Bool(b) => J::Bool(*b),
        Val::Float(f) if f.is_finite() && f.abs() > f32::MAX as f64 => {
            return Err(SceneError::invalid(
                &n.origin,
                object,
                key,
                format!(
                    "{f:e} is too large: rtk computes in f32, whose numbers end at {:e}",
                    f32::MAX
                ),
            ))
        }
        Val::Float(f) => match serde_json::Number::from_f64(*f) {
            Some(x) if f.is_finite() => J::Number(x),
            _ => {
                return Err(SceneError::invalid(
                    &n.origin,
                    object,
                    key,
                    format!("must be a finite number, got {f}"),
                ))
            }
        },
        Val::Datetime => {
            return Err(SceneError::invalid(
                &n.origin,
                object,
                key,
                "date-times are not used by rtk",
            ))
        }
        Val::Arr(a) => J::Array(
            a.iter()
                .enumerate()
                .map(|(i, c)| json(c, object, &format!("{key}[{i}]")))
                .collect::<Result<_, _>>()?,
        ),
        Val::Table(t) => {
            let mut m = serde_json::Map::new();
            for (k, _, v) in t {
                m.insert(k.clone(), json(v, object, &format!("{key}.{k}"))?);
            }
            J::Object(m)
        }
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_shell_s_limit_is_the_kernel_s() {
        assert_eq!(
            super::MAX_COORDINATE as f32,
            rtk_kernel::params::MAX_COORDINATE
        );
    }
}
