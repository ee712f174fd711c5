//! `rtk merge OUT PARTS...`: crop films rendered apart (`rtk render --crop
//! ... -o PART.rtkfilm`, on one machine or many: docs/farm.md) stitched into
//! the full image, bit for bit what a single render gives, because each
//! pixel's f64 sum is copied as it was saved.

use crate::render::film_file::{self, Header};
use crate::render::render_loop::{Accum, Rect};
use crate::shared::output;
use anyhow::{bail, Result};
use std::path::{Path, PathBuf};

/// `rtk merge OUT PARTS...`: stitch crop films (complete, of one scene and
/// settings, not overlapping, covering the image) into the full image.
pub fn run(out: &Path, parts: &[PathBuf]) -> Result<()> {
    let film_out = film_file::is_film_path(out);
    output::check_writable(out)?;
    let Some(first) = parts.first() else {
        bail!("rtk merge: name at least one crop file");
    };
    let mut header0: Option<Header> = None;
    let mut full: Option<Accum> = None;
    let mut covered: Vec<bool> = Vec::new();
    for p in parts {
        let (h, part) = film_file::read(p)?;
        match &header0 {
            Some(h0) => h.check_matches(h0, p, first)?,
            None => {
                header0 = Some(h);
                let rect = Rect::full(h.width, h.height);
                covered = vec![false; rect.len()];
                full = Some(Accum::new(h.width, h.height, rect).map_err(anyhow::Error::msg)?);
            }
        }
        let Some(full) = full.as_mut() else {
            bail!("rtk merge: no film");
        };
        let (min, _) = part.sample_range();
        if min < h.spp {
            bail!(
                "{} is incomplete: some pixels have {min} of {} samples; finish it with --resume before merging",
                p.display(),
                h.spp
            );
        }
        let r = part.rect;
        let w = full.full_width as usize;
        for y in r.y0..r.y1 {
            for x in r.x0..r.x1 {
                let i = (y - r.y0) as usize * r.width() as usize + (x - r.x0) as usize;
                let j = y as usize * w + x as usize;
                if covered[j] {
                    bail!("{} overlaps another crop at pixel ({x}, {y})", p.display());
                }
                covered[j] = true;
                full.sums[j] = part.sums[i];
                full.squares[j] = part.squares[i];
                full.counts[j] = part.counts[i];
            }
        }
    }
    let (Some(h), Some(full)) = (header0, full) else {
        bail!("rtk merge: nothing to merge");
    };
    if let Some(j) = covered.iter().position(|c| !c) {
        let n = covered.iter().filter(|c| !**c).count();
        bail!(
            "the crops leave {n} pixels of the {}x{} image uncovered, the first ({}, {})",
            h.width,
            h.height,
            j % h.width as usize,
            j / h.width as usize
        );
    }
    if film_out {
        film_file::write(out, &h, &full)?;
    } else {
        output::write(&full.into_film(), out)?;
    }
    eprintln!(
        "merged {} crops into {} ({}x{}, {} spp)",
        parts.len(),
        out.display(),
        h.width,
        h.height,
        h.spp
    );
    Ok(())
}
