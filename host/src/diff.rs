//! `rtk diff A B`: the error of an image against a reference, with the
//! metrics `rtk converge` plots (the Mitsuba anchor's), so that one number
//! compares renders from rtk and from other renderers.

use crate::shared::images;
use anyhow::Result;
use std::path::Path;

/// `rtk diff A B`: the metrics of A against the reference B.
pub fn run(a: &Path, b: &Path) -> Result<()> {
    let img = images::read(a)?;
    let reference = images::read(b)?;
    images::check_same_size(
        (img.width, img.height),
        &a.display().to_string(),
        (reference.width, reference.height),
        &b.display().to_string(),
    )?;
    let m = images::metrics(&img.data, &reference.data);
    println!("rmse {}", m.rmse);
    println!("relmse {}", m.relmse);
    Ok(())
}
