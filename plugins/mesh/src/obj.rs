//! OBJ: the text checked line by line before tobj reads it — UTF-8, numbers,
//! faces of at least three vertices, indices in range — so that an error
//! names its line (tobj's errors do not), and a face of two vertices is
//! refused as PLY refuses it, not silently dropped.

use crate::load::MeshData;

/// Read an OBJ file's triangles (polygons triangulated by tobj), positions,
/// and normals and texture coordinates when every group has them.
pub fn read(bytes: &[u8]) -> Result<MeshData, String> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let at = e.valid_up_to();
        let line = bytes[..at].iter().filter(|&&b| b == b'\n').count() + 1;
        format!("line {line}: not UTF-8 text (byte 0x{:02X})", bytes[at])
    })?;
    check(text)?;
    load(text)
}

/// How many of each indexed statement.
#[derive(Default, Clone, Copy)]
struct Counts {
    v: usize,
    vt: usize,
    vn: usize,
}

/// Check every line; the first error names its line.
fn check(text: &str) -> Result<(), String> {
    let mut total = Counts::default();
    for line in text.lines() {
        match line.split_whitespace().next() {
            Some("v") => total.v += 1,
            Some("vt") => total.vt += 1,
            Some("vn") => total.vn += 1,
            _ => {}
        }
    }
    let mut seen = Counts::default();
    for (i, line) in text.lines().enumerate() {
        check_line(line, &mut seen, &total).map_err(|m| format!("line {}: {m}", i + 1))?;
    }
    Ok(())
}

fn check_line(line: &str, seen: &mut Counts, total: &Counts) -> Result<(), String> {
    let mut words = line.split_whitespace();
    match words.next() {
        Some("v") => {
            numbers(words, 3, "a vertex")?;
            seen.v += 1;
        }
        Some("vt") => {
            numbers(words, 2, "a texture coordinate")?;
            seen.vt += 1;
        }
        Some("vn") => {
            numbers(words, 3, "a normal")?;
            seen.vn += 1;
        }
        Some("f") => face(words, seen, total)?,
        _ => {}
    }
    Ok(())
}

/// The first `n` words are numbers.
fn numbers<'a>(words: impl Iterator<Item = &'a str>, n: usize, what: &str) -> Result<(), String> {
    let got: Vec<&str> = words.take(n).collect();
    if got.len() < n {
        return Err(format!("{what} needs {n} numbers, found {}", got.len()));
    }
    match got.iter().find(|w| w.parse::<f32>().is_err()) {
        Some(w) => Err(format!("`{w}` is not a number")),
        None => Ok(()),
    }
}

/// A face: at least three vertices `v`, `v/vt`, `v//vn` or `v/vt/vn`, each
/// index in range (positive: in the file; negative: counted back from this
/// line). Texture and normal indices are checked only when the file has
/// texture coordinates or normals (tobj ignores them otherwise).
fn face<'a>(
    words: impl Iterator<Item = &'a str>,
    seen: &Counts,
    total: &Counts,
) -> Result<(), String> {
    let verts: Vec<&str> = words.collect();
    if verts.len() < 3 {
        return Err(format!(
            "a face needs at least 3 vertices, found {}",
            verts.len()
        ));
    }
    for v in verts {
        let mut parts = v.split('/');
        match parts.next().filter(|s| !s.is_empty()) {
            Some(s) => index(s, seen.v, total.v, "vertex", "vertices")?,
            None => return Err(format!("`{v}` has no vertex index")),
        }
        let kinds = [
            (
                seen.vt,
                total.vt,
                "texture coordinate",
                "texture coordinates",
            ),
            (seen.vn, total.vn, "normal", "normals"),
        ];
        for (part, (seen, total, what, plural)) in parts.zip(kinds) {
            if !part.is_empty() && total > 0 {
                index(part, seen, total, what, plural)?;
            }
        }
    }
    Ok(())
}

fn index(s: &str, seen: usize, total: usize, what: &str, plural: &str) -> Result<(), String> {
    let i: i64 = s
        .parse()
        .map_err(|_| format!("`{s}` is not a {what} index"))?;
    let why = match i {
        0 => "OBJ indices start at 1".to_string(),
        i if i > 0 && i.unsigned_abs() > total as u64 => format!("the file has {total} {plural}"),
        i if i < 0 && i.unsigned_abs() > seen as u64 => {
            format!("only {seen} {plural} come before this line")
        }
        _ => return Ok(()),
    };
    Err(format!("{what} index {i} is out of range: {why}"))
}

/// Read the checked text with tobj.
fn load(text: &str) -> Result<MeshData, String> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let mut r = std::io::Cursor::new(text.as_bytes());
    let (models, _) = tobj::load_obj_buf(&mut r, &opts, |_| Err(tobj::LoadError::GenericFailure))
        .map_err(|e| format!("not a readable OBJ file: {e}"))?;
    let mut m = MeshData {
        positions: vec![],
        tris: vec![],
        normals: None,
        uvs: None,
    };
    if models.iter().all(|md| !md.mesh.normals.is_empty()) {
        m.normals = Some(vec![]);
    }
    if models.iter().all(|md| !md.mesh.texcoords.is_empty()) {
        m.uvs = Some(vec![]);
    }
    for md in &models {
        let base = m.positions.len() as u32;
        let mesh = &md.mesh;
        m.positions
            .extend(mesh.positions.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
        if let Some(ns) = &mut m.normals {
            ns.extend(mesh.normals.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
        }
        if let Some(us) = &mut m.uvs {
            us.extend(mesh.texcoords.chunks_exact(2).map(|c| [c[0], c[1]]));
        }
        m.tris.extend(
            mesh.indices
                .chunks_exact(3)
                .map(|c| [base + c[0], base + c[1], base + c[2]]),
        );
    }
    Ok(m)
}
