//! Affine transforms from a matrix or a list of steps, composed in f64
//! (docs/numerics.md rule 9) and checked: non-finite entries, singular and
//! badly conditioned matrices are refused with the key that caused them.
//! The shell uses this to validate instance transforms; the `transform`
//! plugin uses it to build its matrices.

use crate::PluginError;
use glam::{DAffine3, DMat3, DVec3};
use serde::Deserialize;

/// One step of a transform list. Exactly one key per step.
#[derive(Deserialize, Debug, Clone, Default)]
#[serde(deny_unknown_fields)]
pub struct Step {
    /// Translate by [x, y, z].
    pub translate: Option<[f64; 3]>,
    /// Scale uniformly (a number) or per axis ([x, y, z]).
    pub scale: Option<Scale>,
    /// Rotate about x, degrees.
    pub rotate_x: Option<f64>,
    /// Rotate about y, degrees.
    pub rotate_y: Option<f64>,
    /// Rotate about z, degrees.
    pub rotate_z: Option<f64>,
    /// Rotate about an axis.
    pub rotate: Option<AxisAngle>,
    /// A matrix, row-major: 12 numbers (3 rows of 4) or 16 (last row 0 0 0 1).
    pub matrix: Option<Vec<f64>>,
}

/// A uniform or per-axis scale.
#[derive(Deserialize, Debug, Clone, Copy)]
#[serde(untagged)]
pub enum Scale {
    /// Uniform.
    Uniform(f64),
    /// Per axis.
    Axes([f64; 3]),
}

/// A rotation about an arbitrary axis.
#[derive(Deserialize, Debug, Clone, Copy)]
#[serde(deny_unknown_fields)]
pub struct AxisAngle {
    /// The axis (any length but zero).
    pub axis: [f64; 3],
    /// The angle in degrees.
    pub angle: f64,
}

/// Largest condition number accepted (an f64 estimate): beyond it normals and
/// inverse rays lose all precision in f32 (docs/numerics.md X2).
pub const MAX_CONDITION: f64 = 1e7;

fn finite(key: &str, v: &[f64]) -> Result<(), PluginError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(PluginError::key(key, "must be finite numbers"))
    }
}

/// A matrix given as 12 or 16 row-major numbers.
pub fn matrix_from_rows(key: &str, m: &[f64]) -> Result<DAffine3, PluginError> {
    finite(key, m)?;
    match m.len() {
        12 => {}
        16 => {
            if m[12..] != [0.0, 0.0, 0.0, 1.0] {
                return Err(PluginError::key(
                    key,
                    "the last row must be 0 0 0 1 (affine transforms only)",
                ));
            }
        }
        n => {
            return Err(PluginError::key(
                key,
                format!("needs 12 or 16 numbers (row-major), got {n}"),
            ))
        }
    }
    let cols = DMat3::from_cols(
        DVec3::new(m[0], m[4], m[8]),
        DVec3::new(m[1], m[5], m[9]),
        DVec3::new(m[2], m[6], m[10]),
    );
    Ok(DAffine3::from_mat3_translation(
        cols,
        DVec3::new(m[3], m[7], m[11]),
    ))
}

fn step_matrix(key: &str, s: &Step) -> Result<DAffine3, PluginError> {
    let mut out = Vec::new();
    if let Some(t) = s.translate {
        finite(&format!("{key}.translate"), &t)?;
        out.push(DAffine3::from_translation(t.into()));
    }
    if let Some(sc) = s.scale {
        let v = match sc {
            Scale::Uniform(u) => [u; 3],
            Scale::Axes(a) => a,
        };
        finite(&format!("{key}.scale"), &v)?;
        out.push(DAffine3::from_scale(v.into()));
    }
    for (k, a, f) in [
        (
            "rotate_x",
            s.rotate_x,
            DAffine3::from_rotation_x as fn(f64) -> DAffine3,
        ),
        ("rotate_y", s.rotate_y, DAffine3::from_rotation_y),
        ("rotate_z", s.rotate_z, DAffine3::from_rotation_z),
    ] {
        if let Some(a) = a {
            finite(&format!("{key}.{k}"), &[a])?;
            out.push(f(a.to_radians()));
        }
    }
    if let Some(r) = s.rotate {
        finite(
            &format!("{key}.rotate"),
            &[r.axis[0], r.axis[1], r.axis[2], r.angle],
        )?;
        let axis = DVec3::from(r.axis);
        if axis.length_squared() == 0.0 {
            return Err(PluginError::key(
                format!("{key}.rotate.axis"),
                "must not be zero",
            ));
        }
        out.push(DAffine3::from_axis_angle(
            axis.normalize(),
            r.angle.to_radians(),
        ));
    }
    if let Some(m) = &s.matrix {
        out.push(matrix_from_rows(&format!("{key}.matrix"), m)?);
    }
    match out.len() {
        1 => Ok(out[0]),
        0 => Err(PluginError::key(
            key,
            "a step needs one of translate, scale, rotate_x, rotate_y, rotate_z, rotate, matrix",
        )),
        _ => Err(PluginError::key(
            key,
            "a step takes exactly one key; split it into several steps",
        )),
    }
}

/// Compose steps in order (the first step is applied first), in f64, and
/// check the result. `key` prefixes error key paths (`transform[2].scale`).
pub fn compose(key: &str, steps: &[Step]) -> Result<DAffine3, PluginError> {
    let mut m = DAffine3::IDENTITY;
    for (i, s) in steps.iter().enumerate() {
        let k = format!("{key}[{i}]");
        let sm = step_matrix(&k, s)?;
        m = sm * m;
        check(&k, &m)?;
    }
    Ok(m)
}

/// Refuse non-finite, singular or badly conditioned transforms.
pub fn check(key: &str, m: &DAffine3) -> Result<(), PluginError> {
    let a = m.matrix3;
    let all = a.to_cols_array();
    if !all
        .iter()
        .chain(m.translation.to_array().iter())
        .all(|x| x.is_finite())
    {
        return Err(PluginError::key(
            key,
            "the transform has non-finite entries",
        ));
    }
    let det = a.determinant();
    let norm = |x: &DMat3| x.to_cols_array().iter().map(|v| v * v).sum::<f64>().sqrt();
    if det == 0.0 || !det.is_finite() {
        return Err(PluginError::key(
            key,
            "the transform is singular (determinant 0)",
        ));
    }
    let cond = norm(&a) * norm(&a.inverse());
    if !(cond <= MAX_CONDITION) {
        return Err(PluginError::key(
            key,
            format!("the transform is nearly singular (condition number {cond:.3e} > {MAX_CONDITION:e})"),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(s: &str) -> Step {
        serde_json::from_str(s).unwrap()
    }

    #[test]
    fn order_is_first_step_first() {
        let m = compose(
            "t",
            &[step(r#"{"scale": 2}"#), step(r#"{"translate": [1,0,0]}"#)],
        )
        .unwrap();
        assert_eq!(
            m.transform_point3(DVec3::new(1.0, 0.0, 0.0)),
            DVec3::new(3.0, 0.0, 0.0)
        );
    }

    #[test]
    fn rejects_singular_and_bad_steps() {
        assert!(compose("t", &[step(r#"{"scale": [1, 1, 0]}"#)])
            .unwrap_err()
            .message
            .contains("singular"));
        assert!(compose("t", &[step(r#"{"scale": [1, 1, 1e-9]}"#)])
            .unwrap_err()
            .message
            .contains("nearly"));
        let e = compose("t", &[step(r#"{"scale": 1, "rotate_y": 3}"#)]).unwrap_err();
        assert_eq!(e.key, "t[0]");
        let e = compose("t", &[step(r#"{}"#), step(r#"{"translate":[0,0,0]}"#)]).unwrap_err();
        assert_eq!(e.key, "t[0]");
        assert!(matrix_from_rows("m", &[1.0; 16]).is_err());
    }
}
