//! Parameter parsing and the checks plugins share: every error names the key
//! it concerns, so the shell can point at the TOML file, line and column.

use super::PluginError;
use glam::Vec3;
use rtk_abi::Color;
use serde::de::DeserializeOwned;

/// Largest coordinate accepted: beyond it f32 intersection loses all
/// precision (`docs/numerics.md`, T4).
pub const MAX_COORDINATE: f32 = 1e12;

/// Parse a plugin's parameters from the JSON text the shell passes, with the
/// key path of the first error (unknown keys included).
pub fn parse_params<P: DeserializeOwned>(json: &str) -> Result<P, PluginError> {
    let de = &mut serde_json::Deserializer::from_str(json);
    serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner().to_string();
        // serde_json appends " at line L column C" of the JSON text: useless to
        // the user, whose file is TOML; the shell adds the TOML location.
        let message = match inner.rfind(" at line ") {
            Some(i) => inner[..i].to_string(),
            None => inner,
        };
        let mut key = if path == "." { String::new() } else { path };
        // An unknown key fails before it becomes part of the path: name it.
        if let Some(rest) = message.strip_prefix("unknown field `") {
            if let Some(end) = rest.find('`') {
                let field = &rest[..end];
                let last = key.rsplit(['.', ']']).next().unwrap_or("");
                if last != field {
                    if !key.is_empty() {
                        key.push('.');
                    }
                    key.push_str(field);
                }
            }
        }
        PluginError { key, message }
    })
}

/// Refuse a non-finite number, or one beyond [`MAX_COORDINATE`].
pub fn finite(key: &str, values: &[f32]) -> Result<(), PluginError> {
    for v in values {
        if !v.is_finite() {
            return Err(PluginError::key(key, "must be a finite number"));
        }
        if v.abs() > MAX_COORDINATE {
            return Err(PluginError::key(
                key,
                format!("{v} is beyond what f32 intersection handles (|x| <= 1e12)"),
            ));
        }
    }
    Ok(())
}

/// A position: finite, within [`MAX_COORDINATE`].
pub fn point(key: &str, v: [f32; 3]) -> Result<Vec3, PluginError> {
    finite(key, &v)?;
    Ok(Vec3::from(v))
}

/// A direction: finite and not zero; returned unit length.
pub fn direction(key: &str, v: [f32; 3]) -> Result<Vec3, PluginError> {
    finite(key, &v)?;
    let d = Vec3::from(v);
    if d.length_squared() == 0.0 {
        return Err(PluginError::key(key, "must not be zero"));
    }
    Ok(d.normalize())
}

/// A colour, radiance or intensity: finite and not negative.
pub fn color(key: &str, v: [f32; 3]) -> Result<Color, PluginError> {
    finite(key, &v)?;
    if v.iter().any(|&c| c < 0.0) {
        return Err(PluginError::key(key, "components must not be negative"));
    }
    Ok(Color::from_array(v))
}

/// A reflectance: a colour with every component in [0, 1] (energy conservation).
pub fn reflectance(key: &str, v: [f32; 3]) -> Result<Color, PluginError> {
    let c = color(key, v)?;
    if v.iter().any(|&c| c > 1.0) {
        return Err(PluginError::key(key, "components must be in [0, 1]"));
    }
    Ok(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(serde::Deserialize, Debug)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct P {
        radius: f32,
        inner: Option<Inner>,
    }
    #[derive(serde::Deserialize, Debug)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Inner {
        a: [f32; 2],
    }

    #[test]
    fn errors_name_the_key_path() {
        let e = parse_params::<P>(r#"{"radius": "x"}"#).unwrap_err();
        assert_eq!(e.key, "radius");
        let e = parse_params::<P>(r#"{"radius": 1, "colour": 2}"#).unwrap_err();
        assert_eq!(e.key, "colour");
        assert!(e.message.starts_with("unknown field `colour`"), "{e}");
        let e = parse_params::<P>(r#"{"radius": 1, "inner": {"a": [1, "b"]}}"#).unwrap_err();
        assert_eq!(e.key, "inner.a[1]");
        assert!(!e.message.contains(" at line "), "{e}");
    }

    #[test]
    fn shared_checks() {
        assert!(finite("x", &[1.0, f32::NAN]).is_err());
        assert!(finite("x", &[2e12]).is_err());
        assert_eq!(direction("d", [0.0, 0.0, 2.0]).unwrap(), Vec3::Z);
        assert_eq!(direction("d", [0.0; 3]).unwrap_err().key, "d");
        assert!(color("c", [0.0, -1.0, 0.0]).is_err());
        assert!(reflectance("r", [0.5, 1.5, 0.0]).is_err());
        assert_eq!(
            point("p", [1.0, 2.0, 3.0]).unwrap(),
            Vec3::new(1.0, 2.0, 3.0)
        );
        assert_eq!(PluginError::key("k", "m").to_string(), "k: m");
        assert_eq!(PluginError::msg("m").to_string(), "m");
    }
}
