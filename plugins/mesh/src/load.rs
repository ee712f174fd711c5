//! Reading PLY and OBJ files into flat arrays, with validation. Mesh files
//! come from anywhere, so reading them is bounded: only a regular file of
//! at most [`MAX_MESH_BYTES`] is read (a FIFO would block, `/dev/zero`
//! would never end), every count a file declares is checked against the
//! bytes that back it before anything is allocated, and errors name the
//! line (OBJ) or the element (PLY).

use rtk_kernel::{PluginError, Prepare};
use std::path::Path;

/// Largest mesh file read: 2 GiB. Reading takes about three times the
/// file's size in memory at the peak (the bytes, the parsed records, the
/// arrays built from them).
pub const MAX_MESH_BYTES: u64 = 2 << 30;

/// A loaded triangle mesh.
pub struct MeshData {
    pub positions: Vec<[f32; 3]>,
    pub tris: Vec<[u32; 3]>,
    pub normals: Option<Vec<[f32; 3]>>,
    pub uvs: Option<Vec<[f32; 2]>>,
}

fn err(path: &Path, m: impl std::fmt::Display) -> PluginError {
    PluginError::key("file", format!("{}: {m}", path.display()))
}

/// Read a mesh file through the host (which counts the files read), after
/// checking that it is a regular file within [`MAX_MESH_BYTES`].
pub fn read_file(env: &Prepare, path: &Path) -> Result<Vec<u8>, PluginError> {
    let cannot = |e: std::io::Error| err(path, format!("cannot read the mesh file: {e}"));
    let meta = std::fs::metadata(path).map_err(cannot)?;
    if !meta.is_file() {
        return Err(err(
            path,
            format!(
                "cannot read the mesh file: it is {}, not a regular file",
                file_kind(&meta)
            ),
        ));
    }
    if meta.len() > MAX_MESH_BYTES {
        return Err(err(
            path,
            format!(
                "the mesh file is {} bytes, more than rtk's limit of {} GiB for a mesh",
                meta.len(),
                MAX_MESH_BYTES >> 30
            ),
        ));
    }
    env.read_file(path).map_err(cannot)
}

/// What a file that is not a regular file is, for messages.
fn file_kind(meta: &std::fs::Metadata) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_fifo() {
            return "a FIFO";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if meta.is_dir() {
        "a folder"
    } else {
        "a special file"
    }
}

/// Parse a mesh file's bytes by its extension, and validate the result.
pub fn load(path: &Path, bytes: &[u8]) -> Result<MeshData, PluginError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let m = match ext.as_deref() {
        Some("ply") => crate::ply::read(bytes).map_err(|m| err(path, m))?,
        Some("obj") => crate::obj::read(bytes).map_err(|m| err(path, m))?,
        _ => return Err(err(path, "unknown mesh format: use .ply or .obj")),
    };
    validate(&m).map_err(|m| err(path, m))?;
    Ok(m)
}

/// The checks both formats share: triangles exist, coordinates are finite
/// and within the kernel's range, indices refer to vertices, normals match.
pub fn validate(m: &MeshData) -> Result<(), String> {
    if m.tris.is_empty() {
        return Err("the mesh has no triangles".into());
    }
    for (i, p) in m.positions.iter().enumerate() {
        if p.iter().any(|c| !c.is_finite() || c.abs() > 1e12) {
            return Err(format!(
                "vertex {i} has a non-finite or out-of-range coordinate {p:?} (|x| <= 1e12)"
            ));
        }
    }
    let n = m.positions.len() as u64;
    for (i, t) in m.tris.iter().enumerate() {
        if t.iter().any(|&v| v as u64 >= n) {
            return Err(format!(
                "triangle {i} refers to vertex {t:?}, but there are {n} vertices"
            ));
        }
    }
    if let Some(ns) = &m.normals {
        if ns.len() != m.positions.len() {
            return Err("normal count differs from vertex count".into());
        }
    }
    if let Some(us) = &m.uvs {
        if us.len() != m.positions.len() {
            return Err("texture coordinate count differs from vertex count".into());
        }
    }
    Ok(())
}

/// A parser's message on one line, cut to a readable length (ply-rs's
/// messages span lines and quote the offending line of the file).
pub fn one_line(msg: &str) -> String {
    let joined = msg
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join("; ");
    match joined.char_indices().nth(300) {
        Some((i, _)) => format!("{}…", &joined[..i]),
        None => joined,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const PLY_ASCII: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n4 0 1 2 3\n";
    const OBJ: &str = "# a quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1\nf -4/1/1 -2/3/1 -1/2/1\n";

    fn ply_binary() -> Vec<u8> {
        let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n".to_vec();
        for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
            for c in v {
                b.extend(c.to_le_bytes());
            }
        }
        b.push(3);
        for i in [0u32, 1, 2] {
            b.extend(i.to_le_bytes());
        }
        b
    }

    /// Parse as `name` and, when that succeeds, the result is valid.
    fn never_panics(name: &str, bytes: &[u8]) {
        if let Ok(m) = load(Path::new(name), bytes) {
            assert!(validate(&m).is_ok());
        }
    }

    /// A copy of `base` with bytes replaced, removed, inserted, or cut.
    fn mutated(base: &[u8], edits: &[(usize, u8, u8)], cut: usize) -> Vec<u8> {
        let mut b = base.to_vec();
        for &(at, kind, byte) in edits {
            let at = at % (b.len() + 1);
            match kind % 3 {
                0 if at < b.len() => b[at] = byte,
                1 if at < b.len() => {
                    b.remove(at);
                }
                _ => b.insert(at, byte),
            }
        }
        b.truncate(b.len().saturating_sub(cut % 8));
        b
    }

    #[test]
    fn the_seeds_are_good_meshes() {
        for (name, bytes) in [
            ("a.ply", PLY_ASCII.as_bytes().to_vec()),
            ("b.ply", ply_binary()),
            ("c.obj", OBJ.as_bytes().to_vec()),
        ] {
            let m = load(Path::new(name), &bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!(!m.tris.is_empty(), "{name}");
        }
    }

    #[test]
    fn hostile_files_are_refused_with_the_cause() {
        let cases: [(&str, &[u8], &str); 6] = [
            ("t.obj", b"v 0 0 0\nv 1 0 0\nf 1 2\n", "line 3: a face needs at least 3 vertices"),
            ("u.obj", b"v 0 0 0\nv 1 \xff 0\n", "line 2: not UTF-8"),
            ("o.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "line 4: vertex index 4 is out of range"),
            ("l.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nend_header\n", "truncated or its counts are wrong"),
            ("n.ply", b"ply\nformat ascii 1.0\nelement vertex 1000000000\nend_header\n", "no property"),
            ("x.stl", b"solid", "unknown mesh format"),
        ];
        for (name, bytes, want) in cases {
            let e = load(Path::new(name), bytes)
                .err()
                .unwrap_or_else(|| panic!("{name} loaded"));
            assert!(e.message.contains(want), "{name}: {e}");
            assert_eq!(e.key, "file");
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
            never_panics("a.ply", &bytes);
            never_panics("a.obj", &bytes);
            let mut ply = b"ply\nformat ascii 1.0\n".to_vec();
            ply.extend(&bytes);
            never_panics("b.ply", &ply);
        }

        #[test]
        fn mutated_meshes_never_panic(
            edits in proptest::collection::vec((any::<usize>(), any::<u8>(), any::<u8>()), 1..6),
            cut in any::<usize>(),
        ) {
            never_panics("a.ply", &mutated(PLY_ASCII.as_bytes(), &edits, cut));
            never_panics("b.ply", &mutated(&ply_binary(), &edits, cut));
            never_panics("c.obj", &mutated(OBJ.as_bytes(), &edits, cut));
        }

        #[test]
        fn obj_text_never_panics(lines in proptest::collection::vec(
            "(v|vt|vn|f|l|o|g|#)( -?[0-9]{1,3}(/-?[0-9]{0,2}){0,2}| [a-z.e+-]{1,4}){0,5}", 0..12)) {
            never_panics("d.obj", lines.join("\n").as_bytes());
        }
    }
}
