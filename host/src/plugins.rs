//! `rtk plugins`: what is on the plugin path, as the loader sees it —
//! each plugin's kind, version and documentation, or (`--check`) one line
//! per library saying whether it loads, so a broken install is found
//! before a render needs it.

use crate::shared::printable;
use anyhow::{bail, Result};
use rtk_shell::PluginPath;
use std::path::PathBuf;

/// `rtk plugins`: the plugin path, then every plugin on it with its kind,
/// version and (unless `short`) documentation.
pub fn list(extra: &[PathBuf], short: bool) -> Result<()> {
    let path = PluginPath::standard(extra);
    println!("plugin path (first match wins):");
    for d in &path.dirs {
        println!("  {}", d.display());
    }
    let avail = path.available();
    if avail.is_empty() {
        println!("\nno plugins found");
        return Ok(());
    }
    for (class, file) in avail {
        match rtk_shell::plugins::load(&file, Some(&class)) {
            Ok(p) => {
                println!(
                    "\n{class}  [{}]  v{}  {}",
                    p.kind.name(),
                    p.version,
                    file.display()
                );
                if !short {
                    for l in p.doc.lines() {
                        println!("    {l}");
                    }
                }
            }
            Err(e) => println!("\n{class}  [refused]  {e}"),
        }
    }
    Ok(())
}

/// `rtk plugins --check`: load every plugin library on the path, one line each.
pub fn check(extra: &[PathBuf]) -> Result<()> {
    let path = PluginPath::standard(extra);
    let libs = path.libraries();
    let mut seen = std::collections::BTreeMap::<String, PathBuf>::new();
    let mut broken = 0;
    for (file, class) in &libs {
        let Some(class) = class else {
            broken += 1;
            println!(
                "broken  {}: the file name must be {} with a class name made of letters, digits and _",
                file.display(),
                rtk_shell::plugins::library_file_name("<class>")
            );
            continue;
        };
        let shadow = match seen.get(class) {
            Some(first) => format!("  (shadowed by {}: not used)", first.display()),
            None => {
                seen.insert(class.clone(), file.clone());
                String::new()
            }
        };
        match rtk_shell::plugins::load(file, Some(class)) {
            Ok(p) => println!(
                "ok      {class}  [{}]  v{}  {}{shadow}",
                p.kind.name(),
                p.version,
                file.display()
            ),
            Err(e) => {
                broken += 1;
                let reason = printable(&e.to_string()).replace('\n', " ");
                println!("broken  {class}  {}: {reason}{shadow}", file.display());
            }
        }
    }
    println!(
        "{} plugin libraries: {} ok, {broken} broken",
        libs.len(),
        libs.len() - broken
    );
    if broken > 0 {
        bail!(
            "{broken} of {} plugin libraries on the plugin path cannot be loaded",
            libs.len()
        );
    }
    Ok(())
}
