//! Reading PLY and OBJ files into flat arrays, with validation.

use rtk_kernel::PluginError;
use std::path::Path;

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

pub fn load(path: &Path, bytes: &[u8]) -> Result<MeshData, PluginError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let m = match ext.as_deref() {
        Some("ply") => load_ply(path, bytes)?,
        Some("obj") => load_obj(path, bytes)?,
        _ => return Err(err(path, "unknown mesh format: use .ply or .obj")),
    };
    validate(path, &m)?;
    Ok(m)
}

fn validate(path: &Path, m: &MeshData) -> Result<(), PluginError> {
    if m.tris.is_empty() {
        return Err(err(path, "the mesh has no triangles"));
    }
    for (i, p) in m.positions.iter().enumerate() {
        if p.iter().any(|c| !c.is_finite() || c.abs() > 1e12) {
            return Err(err(
                path,
                format!(
                    "vertex {i} has a non-finite or out-of-range coordinate {p:?} (|x| <= 1e12)"
                ),
            ));
        }
    }
    let n = m.positions.len() as u32;
    for (i, t) in m.tris.iter().enumerate() {
        if t.iter().any(|&v| v >= n) {
            return Err(err(
                path,
                format!("triangle {i} refers to vertex {t:?}, but there are {n} vertices"),
            ));
        }
    }
    if let Some(ns) = &m.normals {
        if ns.len() != m.positions.len() {
            return Err(err(path, "normal count differs from vertex count"));
        }
    }
    Ok(())
}

fn load_ply(path: &Path, bytes: &[u8]) -> Result<MeshData, PluginError> {
    use ply_rs_bw::parser::Parser;
    use ply_rs_bw::ply::{DefaultElement, Property};
    let mut r = std::io::Cursor::new(bytes);
    let ply = Parser::<DefaultElement>::new()
        .read_ply(&mut r)
        .map_err(|e| err(path, format!("not a readable PLY file: {e}")))?;
    let num = |p: Option<&Property>| -> Option<f32> {
        Some(match p? {
            Property::Float(v) => *v,
            Property::Double(v) => *v as f32,
            Property::Int(v) => *v as f32,
            Property::UInt(v) => *v as f32,
            Property::Short(v) => *v as f32,
            Property::UShort(v) => *v as f32,
            Property::Char(v) => *v as f32,
            Property::UChar(v) => *v as f32,
            _ => return None,
        })
    };
    let verts = ply
        .payload
        .get("vertex")
        .ok_or_else(|| err(path, "no `vertex` element"))?;
    let mut positions = Vec::with_capacity(verts.len());
    let has_n = verts.first().is_some_and(|v| v.contains_key("nx"));
    let uv_keys = [("u", "v"), ("s", "t"), ("texture_u", "texture_v")];
    let uvk = verts.first().and_then(|v| {
        uv_keys
            .iter()
            .find(|(a, b)| v.contains_key(*a) && v.contains_key(*b))
    });
    let mut normals = has_n.then(Vec::new);
    let mut uvs = uvk.map(|_| Vec::new());
    for (i, v) in verts.iter().enumerate() {
        let g = |k: &str| {
            num(v.get(k))
                .ok_or_else(|| err(path, format!("vertex {i}: missing or non-numeric `{k}`")))
        };
        positions.push([g("x")?, g("y")?, g("z")?]);
        if let Some(ns) = &mut normals {
            ns.push([g("nx")?, g("ny")?, g("nz")?]);
        }
        if let (Some(us), Some((a, b))) = (&mut uvs, uvk) {
            us.push([g(a)?, g(b)?]);
        }
    }
    let faces = ply
        .payload
        .get("face")
        .ok_or_else(|| err(path, "no `face` element"))?;
    let mut tris = Vec::with_capacity(faces.len());
    for (i, f) in faces.iter().enumerate() {
        let idx: Vec<i64> = match f.get("vertex_indices").or_else(|| f.get("vertex_index")) {
            Some(Property::ListInt(l)) => l.iter().map(|&x| x as i64).collect(),
            Some(Property::ListUInt(l)) => l.iter().map(|&x| x as i64).collect(),
            Some(Property::ListShort(l)) => l.iter().map(|&x| x as i64).collect(),
            Some(Property::ListUShort(l)) => l.iter().map(|&x| x as i64).collect(),
            Some(Property::ListUChar(l)) => l.iter().map(|&x| x as i64).collect(),
            Some(Property::ListChar(l)) => l.iter().map(|&x| x as i64).collect(),
            _ => {
                return Err(err(
                    path,
                    format!("face {i}: missing `vertex_indices` list"),
                ))
            }
        };
        if idx.len() < 3 {
            return Err(err(path, format!("face {i} has {} vertices", idx.len())));
        }
        if idx.iter().any(|&x| x < 0 || x > u32::MAX as i64) {
            return Err(err(path, format!("face {i} has a negative or huge index")));
        }
        // Fan-triangulate polygons.
        for k in 1..idx.len() - 1 {
            tris.push([idx[0] as u32, idx[k] as u32, idx[k + 1] as u32]);
        }
    }
    Ok(MeshData {
        positions,
        tris,
        normals,
        uvs,
    })
}

fn load_obj(path: &Path, bytes: &[u8]) -> Result<MeshData, PluginError> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let mut r = std::io::Cursor::new(bytes);
    let (models, _) = tobj::load_obj_buf(&mut r, &opts, |_| Err(tobj::LoadError::GenericFailure))
        .map_err(|e| err(path, format!("not a readable OBJ file: {e}")))?;
    let mut m = MeshData {
        positions: vec![],
        tris: vec![],
        normals: None,
        uvs: None,
    };
    let all_n = models.iter().all(|md| !md.mesh.normals.is_empty());
    let all_uv = models.iter().all(|md| !md.mesh.texcoords.is_empty());
    if all_n {
        m.normals = Some(vec![]);
    }
    if all_uv {
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
