//! `rtk new KIND NAME`: write a ready-to-build out-of-tree plugin crate (its
//! Cargo.toml against this rtk's kernel, the smallest correct implementation
//! of the kind, its README.md and a scene using it). The templates live in
//! `host/templates/`.

use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};

/// The arguments of `rtk new`.
#[derive(clap::Args)]
pub struct NewArgs {
    /// The kind of plugin.
    #[arg(value_enum)]
    pub kind: Kind,
    /// The class name (an identifier: letters, digits, _; not a built-in class).
    pub name: String,
    /// The folder to write (default: ./rtk-NAME); must not exist or be empty.
    #[arg(long, value_name = "DIR")]
    pub dir: Option<PathBuf>,
}

/// The plugin kinds `rtk new` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Kind {
    /// A primitive (a sphere-like one).
    Object,
    /// An acceleration structure (an exhaustive list).
    Aggregate,
    /// A material (a Lambertian one).
    Shader,
    /// An integrator (shading normals as colours).
    Integrator,
    /// A camera (a pinhole).
    Camera,
    /// A light (a point light).
    Light,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::Object => "object",
            Kind::Aggregate => "aggregate",
            Kind::Shader => "shader",
            Kind::Integrator => "integrator",
            Kind::Camera => "camera",
            Kind::Light => "light",
        }
    }

    /// (src/lib.rs, README.md) templates.
    fn templates(self) -> (&'static str, &'static str) {
        match self {
            Kind::Object => (
                include_str!("../templates/object.rs"),
                include_str!("../templates/object.README.md"),
            ),
            Kind::Aggregate => (
                include_str!("../templates/aggregate.rs"),
                include_str!("../templates/aggregate.README.md"),
            ),
            Kind::Shader => (
                include_str!("../templates/shader.rs"),
                include_str!("../templates/shader.README.md"),
            ),
            Kind::Integrator => (
                include_str!("../templates/integrator.rs"),
                include_str!("../templates/integrator.README.md"),
            ),
            Kind::Camera => (
                include_str!("../templates/camera.rs"),
                include_str!("../templates/camera.README.md"),
            ),
            Kind::Light => (
                include_str!("../templates/light.rs"),
                include_str!("../templates/light.README.md"),
            ),
        }
    }
}

const CARGO_TOML: &str = include_str!("../templates/Cargo.toml.tmpl");
const SCENE: &str = include_str!("../templates/scene.toml.tmpl");

/// The classes rtk ships (the folders of `plugins/`): a new plugin of the
/// same name would shadow or be shadowed by one of them.
pub(crate) const BUILTIN_CLASSES: &[&str] = &[
    "area",
    "bicubic",
    "bvh",
    "conductor",
    "cone",
    "constant",
    "csg",
    "cylinder",
    "dielectric",
    "directional",
    "disk",
    "distributed",
    "envmap",
    "flat",
    "fractal",
    "grid",
    "kdtree",
    "lambert",
    "list",
    "mesh",
    "motion",
    "normals",
    "octree",
    "path",
    "phong",
    "pinhole",
    "plastic",
    "point",
    "polygon",
    "projector",
    "raycls",
    "roughconductor",
    "roughdielectric",
    "roughplastic",
    "slabs",
    "sphere",
    "thinlens",
    "torus",
    "transform",
    "whitted",
];

/// The kernel crate of this rtk, an absolute path known at build time.
fn kernel_dir() -> PathBuf {
    let host = Path::new(env!("CARGO_MANIFEST_DIR"));
    let k = host.parent().unwrap_or(host).join("kernel");
    std::fs::canonicalize(&k).unwrap_or(k)
}

/// A TOML basic string holding `s`.
fn toml_quote(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if c.is_control() => out.push_str(&format!("\\u{:04X}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// Refuse a name that is no identifier or that names a built-in class (or
/// any class already on the standard plugin path).
fn check_name(name: &str) -> Result<()> {
    if !rtk_shell::plugins::is_identifier(name) {
        bail!(
            "`{}` is not a class name: use letters, digits and _ (not starting with a digit)",
            rtk_shell::error::shown(name, 80)
        );
    }
    if BUILTIN_CLASSES.contains(&name) {
        bail!("`{name}` is a built-in class of rtk: choose another name (a plugin of the same name would shadow it)");
    }
    if let Some(p) = rtk_shell::PluginPath::standard(&[]).find(name) {
        bail!(
            "`{name}` is already a class on the plugin path ({}): choose another name",
            p.display()
        );
    }
    Ok(())
}

/// Fill the placeholders of a template.
fn fill(t: &str, kind: Kind, name: &str) -> String {
    let pick = |k: Kind, builtin: &'static str| if kind == k { name } else { builtin };
    t.replace("__KERNEL__", &toml_quote(&kernel_dir().to_string_lossy()))
        .replace("__KIND__", kind.name())
        .replace("__INTEGRATOR__", pick(Kind::Integrator, "whitted"))
        .replace("__CAMERA__", pick(Kind::Camera, "pinhole"))
        .replace("__LIGHT__", pick(Kind::Light, "point"))
        .replace("__SHADER__", pick(Kind::Shader, "lambert"))
        .replace("__OBJECT__", pick(Kind::Object, "sphere"))
        .replace("__AGG__", pick(Kind::Aggregate, "list"))
        .replace("__NAME__", name)
}

/// Run `rtk new`.
pub fn run(a: NewArgs) -> Result<()> {
    check_name(&a.name)?;
    let dir = a
        .dir
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("rtk-{}", a.name)));
    if dir.exists() {
        let empty = std::fs::read_dir(&dir)
            .with_context(|| format!("{} exists and is not a readable folder", dir.display()))?
            .next()
            .is_none();
        if !empty {
            bail!(
                "{} exists and is not empty: rtk new writes a new crate into an empty or new folder",
                dir.display()
            );
        }
    }
    let (lib, readme) = a.kind.templates();
    let files: [(&str, &str); 4] = [
        ("Cargo.toml", CARGO_TOML),
        ("src/lib.rs", lib),
        ("README.md", readme),
        ("scene.toml", SCENE),
    ];
    std::fs::create_dir_all(dir.join("src"))
        .with_context(|| format!("creating {}", dir.display()))?;
    for (rel, t) in files {
        let p = dir.join(rel);
        std::fs::write(&p, fill(t, a.kind, &a.name))
            .with_context(|| format!("writing {}", p.display()))?;
    }
    println!(
        "wrote the {} plugin `{}` in {}:\n  Cargo.toml  (cdylib rtk_{}, rtk-kernel at {})\n  src/lib.rs\n  README.md   (its parameters; the export macro includes it)\n  scene.toml\nnext:\n  cd {} && cargo build --release\n  rtk render scene.toml --plugin-path target/release",
        a.kind.name(),
        a.name,
        dir.display(),
        a.name,
        kernel_dir().display(),
        dir.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    /// The list names every folder of `plugins/`, in order (a new plugin
    /// added without it would let `rtk new` shadow it).
    #[test]
    fn builtin_classes_are_the_plugin_folders() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../plugins");
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, super::BUILTIN_CLASSES);
    }
}
