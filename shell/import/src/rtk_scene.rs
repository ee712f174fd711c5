//! The rtk scene an importer builds, and its TOML text: sections in the
//! order docs/scene-format.md documents them, one definition per table,
//! instances one per line, so that the file reads like one written by hand.

use std::fmt::Write;
use std::path::{Path, PathBuf};
use toml::Value;

/// A table's keys and values, in the order they are written.
pub type Keys = Vec<(String, Value)>;

/// An rtk scene under construction.
#[derive(Debug, Default)]
pub struct RtkScene {
    /// Comment lines at the top (without `# `).
    pub header: Vec<String>,
    /// `[params]`.
    pub params: Keys,
    /// `[render]`.
    pub render: Keys,
    /// `[cameras.*]`.
    pub cameras: Vec<(String, Keys)>,
    /// `[lights.*]`.
    pub lights: Vec<(String, Keys)>,
    /// `[shaders.*]`.
    pub shaders: Vec<(String, Keys)>,
    /// `[objects.*]`.
    pub objects: Vec<(String, Keys)>,
}

impl RtkScene {
    /// Is `name` taken by a definition of any section?
    pub fn is_taken(&self, name: &str) -> bool {
        [&self.cameras, &self.lights, &self.shaders, &self.objects]
            .iter()
            .any(|s| s.iter().any(|(n, _)| n == name))
    }

    /// A definition name from `hint` (an id, a file stem): letters,
    /// digits, `_` and `-`, unique across sections.
    pub fn fresh_name(&self, hint: &str) -> String {
        let mut base: String = hint
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        if base.is_empty() || base.starts_with(|c: char| c.is_ascii_digit()) {
            base.insert(0, '_');
        }
        if !self.is_taken(&base) {
            return base;
        }
        (2..)
            .map(|k| format!("{base}_{k}"))
            .find(|n| !self.is_taken(n))
            .expect("a free name")
    }

    /// The TOML text.
    pub fn to_toml(&self) -> String {
        let mut s = String::new();
        for h in &self.header {
            let _ = writeln!(s, "# {h}");
        }
        if !self.params.is_empty() {
            table(&mut s, "params", &self.params);
        }
        table(&mut s, "render", &self.render);
        for (section, defs) in [
            ("cameras", &self.cameras),
            ("lights", &self.lights),
            ("shaders", &self.shaders),
            ("objects", &self.objects),
        ] {
            for (name, keys) in defs {
                table(&mut s, &format!("{section}.{name}"), keys);
            }
        }
        s
    }
}

/// `[name]` and its keys; arrays of tables (instances) one per line.
fn table(s: &mut String, name: &str, keys: &Keys) {
    let _ = writeln!(s, "\n[{name}]");
    for (k, v) in keys {
        match v {
            Value::Array(items) if items.iter().all(|i| i.is_table()) && !items.is_empty() => {
                let _ = writeln!(s, "{} = [", key(k));
                for i in items {
                    let _ = writeln!(s, "  {},", inline(i));
                }
                let _ = writeln!(s, "]");
            }
            v => {
                let _ = writeln!(s, "{} = {}", key(k), inline(v));
            }
        }
    }
}

/// A key, quoted unless bare.
fn key(k: &str) -> String {
    let bare = !k.is_empty()
        && k.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    if bare {
        k.to_string()
    } else {
        Value::String(k.to_string()).to_string()
    }
}

/// A value on one line (tables inline, keys in order).
fn inline(v: &Value) -> String {
    match v {
        Value::Table(t) => {
            let items: Vec<String> = t
                .iter()
                .map(|(k, v)| format!("{} = {}", key(k), inline(v)))
                .collect();
            format!("{{ {} }}", items.join(", "))
        }
        Value::Array(a) => {
            let items: Vec<String> = a.iter().map(inline).collect();
            format!("[{}]", items.join(", "))
        }
        Value::Float(f) => float(*f),
        v => v.to_string(),
    }
}

/// A float as TOML writes it, always with a decimal point.
fn float(f: f64) -> String {
    let s = format!("{f:?}");
    if s.contains(['.', 'e', 'E']) || !f.is_finite() {
        s
    } else {
        format!("{s}.0")
    }
}

/// A file's name as a scene read from folder `out_dir` names it: relative
/// to that folder where both resolve, else absolute; a leading `$`
/// doubled (rtk reads `"$name"` as a scene parameter, `"$$"` as `$`).
pub fn file_name(path: &Path, out_dir: &Path) -> String {
    let name = relative_path(path, out_dir).display().to_string();
    if name.starts_with('$') {
        format!("${name}")
    } else {
        name
    }
}

/// `target` relative to folder `base` when both canonicalize, else
/// `target` made absolute.
fn relative_path(target: &Path, base: &Path) -> PathBuf {
    let (Ok(t), Ok(b)) = (std::fs::canonicalize(target), std::fs::canonicalize(base)) else {
        return std::path::absolute(target).unwrap_or_else(|_| target.to_path_buf());
    };
    let (tc, bc): (Vec<_>, Vec<_>) = (t.components().collect(), b.components().collect());
    let common = tc.iter().zip(&bc).take_while(|(a, b)| a == b).count();
    if common == 0 {
        return t;
    }
    let mut out = PathBuf::new();
    for _ in common..bc.len() {
        out.push("..");
    }
    for c in &tc[common..] {
        out.push(c.as_os_str());
    }
    out
}

/// An `[x, y, z]` float array.
pub fn vec3(v: [f64; 3]) -> Value {
    Value::Array(v.iter().map(|x| Value::Float(*x)).collect())
}

/// An inline table from keys in order.
pub fn inline_table(keys: Keys) -> Value {
    let mut t = toml::Table::new();
    for (k, v) in keys {
        t.insert(k, v);
    }
    Value::Table(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_text_parses_back_as_the_same_values() {
        let mut s = RtkScene::default();
        s.header.push("imported".into());
        s.params.push(("spp".into(), Value::Integer(32)));
        s.render.push(("spp".into(), Value::String("$spp".into())));
        s.objects.push((
            "scene".into(),
            vec![(
                "children".into(),
                Value::Array(vec![inline_table(vec![
                    ("object".into(), Value::String("a".into())),
                    (
                        "transform".into(),
                        Value::Array(vec![inline_table(vec![(
                            "scale".into(),
                            Value::Float(2.0),
                        )])]),
                    ),
                ])]),
            )],
        ));
        let text = s.to_toml();
        let back: toml::Table = toml::from_str(&text).unwrap();
        assert_eq!(back["params"]["spp"].as_integer(), Some(32));
        assert_eq!(back["render"]["spp"].as_str(), Some("$spp"));
        let c = &back["objects"]["scene"]["children"][0];
        assert_eq!(c["transform"][0]["scale"].as_float(), Some(2.0));
        assert!(text.starts_with("# imported\n"));
        assert_eq!(s.fresh_name("scene"), "scene_2");
        assert_eq!(s.fresh_name("9 lives"), "_9_lives");
    }
}
