//! The classic patch-file format of Newell's teapot: the number of patches,
//! then 16 1-based vertex indices per patch, then the number of vertices and
//! x, y, z per vertex. Numbers are separated by commas and/or white space.

/// Patches as 16 0-based indices each, and the vertices.
pub type Parsed = (Vec<[u32; 16]>, Vec<[f64; 3]>);

/// Most patches or vertices a file may declare.
const MAX_COUNT: usize = 1 << 24;

pub fn parse(text: &str) -> Result<Parsed, String> {
    let mut toks = text
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty());
    let mut next = |what: &str| -> Result<&str, String> {
        toks.next()
            .ok_or_else(|| format!("the file ends before {what}"))
    };
    let count = |s: &str, what: &str| -> Result<usize, String> {
        let n: usize = s
            .parse()
            .map_err(|_| format!("{what}: expected a count, got `{s}`"))?;
        if n == 0 || n > MAX_COUNT {
            return Err(format!("{what}: must be from 1 to {MAX_COUNT}, got {n}"));
        }
        Ok(n)
    };
    let np = count(next("the patch count")?, "patch count")?;
    let mut idx = Vec::with_capacity(np);
    for p in 0..np {
        let mut q = [0u32; 16];
        for (k, slot) in q.iter_mut().enumerate() {
            let s = next(&format!("patch {} index {}", p + 1, k + 1))?;
            let i: u32 = s.parse().map_err(|_| {
                format!(
                    "patch {} index {}: expected an integer, got `{s}`",
                    p + 1,
                    k + 1
                )
            })?;
            if i == 0 {
                return Err(format!("patch {}: indices are 1-based, got 0", p + 1));
            }
            *slot = i - 1;
        }
        idx.push(q);
    }
    let nv = count(next("the vertex count")?, "vertex count")?;
    let mut verts = Vec::with_capacity(nv);
    for v in 0..nv {
        let mut p = [0.0f64; 3];
        for (k, c) in p.iter_mut().enumerate() {
            let s = next(&format!("vertex {}", v + 1))?;
            let x: f64 = s
                .parse()
                .map_err(|_| format!("vertex {}: expected a number, got `{s}`", v + 1))?;
            if !x.is_finite() || x.abs() > 1e12 {
                return Err(format!(
                    "vertex {} coordinate {}: must be finite, |x| <= 1e12, got {x}",
                    v + 1,
                    k + 1
                ));
            }
            *c = x;
        }
        verts.push(p);
    }
    for (p, q) in idx.iter().enumerate() {
        if let Some(&i) = q.iter().find(|&&i| i as usize >= nv) {
            return Err(format!(
                "patch {} refers to vertex {}, but there are {nv}",
                p + 1,
                i + 1
            ));
        }
    }
    Ok((idx, verts))
}
