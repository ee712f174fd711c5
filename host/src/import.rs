//! `rtk import FILE.xml [-o scene.toml]`: a Mitsuba scene translated to
//! rtk's TOML (the `rtk-import` crate), for a person to read and edit; and
//! the options `rtk render FILE.xml` shares with it.

use anyhow::{bail, Result};
use std::path::{Path, PathBuf};

/// How a scene of another renderer is translated (`rtk import`, and
/// `rtk render` of such a scene).
#[derive(clap::Args, Clone, Default)]
pub struct ImportOptions {
    /// Drop what cannot be translated exactly, with a warning line each,
    /// instead of refusing the scene.
    #[arg(long)]
    pub lenient: bool,
    /// Set a scene parameter of the imported file (Mitsuba's `-D
    /// name=value`, overriding its `<default>`), repeatable.
    #[arg(short = 'D', long = "define", value_name = "NAME=VALUE")]
    pub define: Vec<String>,
}

impl ImportOptions {
    /// The importer's options, its file names relative to `out_dir`.
    pub fn options(&self, out_dir: &Path) -> Result<rtk_import::Options> {
        let params = (self.define.iter())
            .map(|d| match d.split_once('=') {
                Some((n, v)) if !n.trim().is_empty() => Ok((n.trim().to_string(), v.to_string())),
                _ => bail!("-D {d}: expected NAME=VALUE"),
            })
            .collect::<Result<_>>()?;
        Ok(rtk_import::Options {
            lenient: self.lenient,
            params,
            out_dir: out_dir.to_path_buf(),
        })
    }

    /// Refuse the options for a scene that is not imported.
    pub fn check_unused(&self, scene: &Path) -> Result<()> {
        if self.lenient || !self.define.is_empty() {
            bail!(
                "--lenient and -D apply to scenes rtk imports (Mitsuba .xml); {} is an rtk scene",
                scene.display()
            );
        }
        Ok(())
    }
}

/// The arguments of `rtk import`.
#[derive(clap::Args)]
pub struct ImportArgs {
    /// The scene: Mitsuba XML (.xml) or pbrt-v4 (.pbrt).
    scene: PathBuf,
    /// Where to write the rtk scene (.toml); default: standard output.
    /// File names in it are relative to its folder.
    #[arg(short, long, value_name = "FILE.toml")]
    output: Option<PathBuf>,
    #[command(flatten)]
    opts: ImportOptions,
}

/// Translate `path` for reading from folder `out_dir`; warnings go to
/// stderr.
pub fn translate(path: &Path, opts: &ImportOptions, out_dir: &Path) -> Result<String> {
    let imported = rtk_import::import(path, &opts.options(out_dir)?)?;
    for w in &imported.warnings {
        eprintln!("{w}");
    }
    Ok(imported.toml)
}

/// `rtk import`.
pub fn run(a: &ImportArgs) -> Result<()> {
    let out_dir = match &a.output {
        Some(o) => match o.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        },
        None => PathBuf::from("."),
    };
    if let Some(o) = &a.output {
        crate::shared::output::check_can_create(o, "output")?;
    }
    let toml = translate(&a.scene, &a.opts, &out_dir)?;
    match &a.output {
        Some(o) => {
            crate::shared::output::write_atomically(o, |tmp| Ok(std::fs::write(tmp, &toml)?))
        }
        None => {
            print!("{toml}");
            Ok(())
        }
    }
}
