//! Closed-form references for `rtk converge --analytic SPEC`: images whose
//! every pixel is known exactly for a scene built to match.
//!
//! A spec is `NAME` or `NAME:ARGS`; ARGS are comma-separated, either plain
//! numbers or `key=value` where a value is one number (grey) or three (RGB):
//! `furnace:le=1,albedo=0.5`, `furnace:le=1,0.5,0.25,albedo=0.8,0.8,0.5`.
//!
//! | name | arguments | every pixel | the scene it fits |
//! |---|---|---|---|
//! | `furnace` | `le=R[,G,B]`, `albedo=A[,B,C]` (each 0 <= A < 1) | `le / (1 - albedo)` | white furnace: the camera inside a closed diffuse shape of albedo A emitting Le everywhere |
//! | `constant` | `R,G,B` or `V` | that colour | anything known to be uniform (an empty scene's background) |
//!
//! A new reference is one more [`Analytic`] variant, its row in [`KINDS`],
//! an arm in [`Analytic::parse`] and one in [`Analytic::radiance`].

use anyhow::{bail, Result};

/// The names and argument forms, for messages and help.
pub const KINDS: &[(&str, &str)] = &[
    ("furnace", "furnace:le=R[,G,B],albedo=A[,B,C]"),
    ("constant", "constant:R,G,B (or constant:V)"),
];

/// A closed-form reference.
#[derive(Debug, Clone, PartialEq)]
pub enum Analytic {
    /// White furnace: a closed diffuse enclosure of albedo `albedo` (each
    /// channel in [0, 1)) emitting `le`, seen from inside: L = Le / (1 - albedo).
    Furnace {
        /// Emitted radiance.
        le: [f64; 3],
        /// Diffuse albedo.
        albedo: [f64; 3],
    },
    /// A uniform colour.
    Constant([f64; 3]),
}

impl Analytic {
    /// Parse a spec; errors name the spec and say what was expected.
    pub fn parse(spec: &str) -> Result<Analytic> {
        Self::parse_inner(spec).map_err(|e| anyhow::anyhow!("--analytic `{spec}`: {e:#}"))
    }

    fn parse_inner(spec: &str) -> Result<Analytic> {
        let (name, args) = spec.split_once(':').unwrap_or((spec, ""));
        let args = Args::parse(args)?;
        let a = match name.trim() {
            "furnace" => {
                args.no_plain("furnace")?;
                args.only(&["le", "albedo"])?;
                let le = args.rgb("le")?;
                let albedo = args.rgb("albedo")?;
                if le.iter().any(|v| *v < 0.0) {
                    bail!("`le` must not be negative");
                }
                if albedo.iter().any(|v| !(*v >= 0.0 && *v < 1.0)) {
                    bail!("`albedo` must be at least 0 and below 1 (the series 1/(1-albedo) diverges at 1)");
                }
                Analytic::Furnace { le, albedo }
            }
            "constant" => {
                if !args.keyed.is_empty() {
                    bail!("takes a colour R,G,B or a value V, not keys");
                }
                let c = rgb_of(&args.plain, "the colour")?;
                if c.iter().any(|v| *v < 0.0) {
                    bail!("the colour must not be negative (it is a radiance)");
                }
                Analytic::Constant(c)
            }
            "" => bail!("no reference named; {}", known()),
            other => bail!("unknown reference `{other}`; {}", known()),
        };
        Ok(a)
    }

    /// The radiance of every pixel.
    pub fn radiance(&self) -> [f64; 3] {
        match self {
            Analytic::Furnace { le, albedo } => [0, 1, 2].map(|c| le[c] / (1.0 - albedo[c])),
            Analytic::Constant(c) => *c,
        }
    }
}

fn known() -> String {
    let forms: Vec<&str> = KINDS.iter().map(|(_, f)| *f).collect();
    format!("known: {}", forms.join("; "))
}

/// A spec's arguments: plain numbers before any key, and keys with their numbers.
struct Args {
    plain: Vec<f64>,
    keyed: Vec<(String, Vec<f64>)>,
}

impl Args {
    fn parse(s: &str) -> Result<Args> {
        let mut a = Args {
            plain: vec![],
            keyed: vec![],
        };
        if s.trim().is_empty() {
            return Ok(a);
        }
        for item in s.split(',') {
            let (key, value) = match item.split_once('=') {
                Some((k, v)) => (Some(k.trim()), v.trim()),
                None => (None, item.trim()),
            };
            let v: f64 = value
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite())
                .ok_or_else(|| anyhow::anyhow!("`{value}` is not a finite number"))?;
            match key {
                Some(k) => {
                    if k.is_empty() {
                        bail!("`={value}` has no key");
                    }
                    if a.keyed.iter().any(|(n, _)| n == k) {
                        bail!("`{k}` given twice");
                    }
                    a.keyed.push((k.to_string(), vec![v]));
                }
                None => match a.keyed.last_mut() {
                    Some((_, vs)) => vs.push(v),
                    None => a.plain.push(v),
                },
            }
        }
        Ok(a)
    }

    fn no_plain(&self, name: &str) -> Result<()> {
        if !self.plain.is_empty() {
            bail!("{name} takes keys (key=value), not bare numbers");
        }
        Ok(())
    }

    fn only(&self, keys: &[&str]) -> Result<()> {
        if let Some((k, _)) = self.keyed.iter().find(|(k, _)| !keys.contains(&k.as_str())) {
            bail!("unknown key `{k}` (keys: {})", keys.join(", "));
        }
        Ok(())
    }

    fn rgb(&self, key: &str) -> Result<[f64; 3]> {
        match self.keyed.iter().find(|(k, _)| k == key) {
            Some((_, vs)) => rgb_of(vs, &format!("`{key}`")),
            None => bail!("missing `{key}=`"),
        }
    }
}

/// One value (grey) or three (RGB).
fn rgb_of(vs: &[f64], what: &str) -> Result<[f64; 3]> {
    match *vs {
        [v] => Ok([v; 3]),
        [r, g, b] => Ok([r, g, b]),
        _ => bail!("{what} needs 1 or 3 numbers, got {}", vs.len()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn furnace_grey_and_rgb() {
        let a = Analytic::parse("furnace:le=1,albedo=0.5").unwrap();
        assert_eq!(a.radiance(), [2.0; 3]);
        let a = Analytic::parse("furnace:le=1,0.5,0.25,albedo=0.5,0.75,0").unwrap();
        assert_eq!(a.radiance(), [2.0, 2.0, 0.25]);
        let a = Analytic::parse("furnace:albedo=0,le=3").unwrap();
        assert_eq!(a.radiance(), [3.0; 3]);
    }

    #[test]
    fn constant() {
        assert_eq!(
            Analytic::parse("constant:0,0.5,1").unwrap().radiance(),
            [0.0, 0.5, 1.0]
        );
        assert_eq!(
            Analytic::parse("constant:0.25").unwrap().radiance(),
            [0.25; 3]
        );
    }

    #[test]
    fn bad_specs_name_the_spec() {
        for (spec, says) in [
            ("bogus", "unknown reference `bogus`"),
            ("", "no reference named"),
            ("furnace:le=1,albedo=1", "below 1"),
            ("furnace:le=1,albedo=-0.1", "below 1"),
            ("furnace:le=-1,albedo=0.5", "negative"),
            ("furnace:le=1", "missing `albedo=`"),
            ("furnace:le=1,2,albedo=0.5", "1 or 3 numbers"),
            ("furnace:le=1,albedo=0.5,gain=2", "unknown key `gain`"),
            ("furnace:1,2,3", "not bare numbers"),
            ("furnace:le=1,le=2,albedo=0", "twice"),
            ("constant:1,2", "1 or 3 numbers"),
            ("constant:", "1 or 3 numbers"),
            ("constant:x", "`x` is not a finite number"),
            ("constant:nan", "not a finite number"),
            ("constant:-1", "must not be negative"),
            ("constant:1,-0.5,1", "must not be negative"),
            ("constant:v=1", "not keys"),
        ] {
            let e = format!("{:#}", Analytic::parse(spec).unwrap_err());
            assert!(e.starts_with(&format!("--analytic `{spec}`:")), "{e}");
            assert!(e.contains(says), "{spec}: {e}");
        }
        let e = format!("{:#}", Analytic::parse("bogus").unwrap_err());
        assert!(e.contains("furnace:le=") && e.contains("constant:"), "{e}");
    }
}
