//! PLY: the header read by ply-rs, its counts checked against the bytes
//! that follow it, then the `vertex` and `face` elements read into compact
//! records. (ply-rs's default element is a hash map per vertex, about 30
//! times the file's size in memory; and an element of no properties
//! declared a billion times would be "read" from no bytes at all.)

use crate::load::{one_line, MeshData};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{
    ElementDef, Encoding, Header, Property, PropertyAccess, PropertyAccessResult, PropertyType,
    ScalarType,
};

/// The vertex properties rtk reads, by slot.
const SLOTS: [&str; 12] = [
    "x",
    "y",
    "z",
    "nx",
    "ny",
    "nz",
    "u",
    "v",
    "s",
    "t",
    "texture_u",
    "texture_v",
];
/// Texture coordinate pairs, in order of preference (slots).
const UV_PAIRS: [(usize, usize); 3] = [(6, 7), (8, 9), (10, 11)];

/// One vertex: the properties of [`SLOTS`] it has, flagged in `has`.
#[derive(Default)]
struct Vertex {
    v: [f32; SLOTS.len()],
    has: u16,
}

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Self::default()
    }
    fn set_property(&mut self, name: &str, p: Property) -> PropertyAccessResult {
        let Some(i) = SLOTS.iter().position(|s| *s == name) else {
            return PropertyAccessResult::Ignored;
        };
        if let Some(x) = scalar(&p) {
            self.v[i] = x;
            self.has |= 1 << i;
        }
        PropertyAccessResult::Set
    }
}

fn scalar(p: &Property) -> Option<f32> {
    Some(match p {
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
}

/// One face: its vertex indices (the first three inline: most faces are
/// triangles), or the first index that cannot be one.
#[derive(Default)]
struct Face {
    first: [u32; 3],
    rest: Vec<u32>,
    count: usize,
    bad: Option<i64>,
    has: bool,
}

impl PropertyAccess for Face {
    fn new() -> Self {
        Self::default()
    }
    fn set_property(&mut self, name: &str, p: Property) -> PropertyAccessResult {
        if name != "vertex_indices" && name != "vertex_index" {
            return PropertyAccessResult::Ignored;
        }
        let list: Vec<i64> = match p {
            Property::ListInt(l) => l.into_iter().map(i64::from).collect(),
            Property::ListUInt(l) => l.into_iter().map(i64::from).collect(),
            Property::ListShort(l) => l.into_iter().map(i64::from).collect(),
            Property::ListUShort(l) => l.into_iter().map(i64::from).collect(),
            Property::ListUChar(l) => l.into_iter().map(i64::from).collect(),
            Property::ListChar(l) => l.into_iter().map(i64::from).collect(),
            _ => return PropertyAccessResult::Ignored,
        };
        self.has = true;
        self.count = list.len();
        self.bad = list.iter().copied().find(|&x| u32::try_from(x).is_err());
        if self.bad.is_none() {
            for (k, &x) in list.iter().enumerate() {
                match self.first.get_mut(k) {
                    Some(slot) => *slot = x as u32,
                    None => self.rest.push(x as u32),
                }
            }
        }
        PropertyAccessResult::Set
    }
}

/// Other elements: read past, nothing kept.
struct Skip;

impl PropertyAccess for Skip {
    fn new() -> Self {
        Skip
    }
}

fn unreadable(e: ply_rs_bw::parser::ParseError) -> String {
    format!("not a readable PLY file: {}", one_line(&e.to_string()))
}

/// Read a PLY file's triangles (polygons fan-triangulated), positions and,
/// where present, normals and texture coordinates.
pub fn read(bytes: &[u8]) -> Result<MeshData, String> {
    let mut reader = Reader::new(std::io::Cursor::new(bytes));
    let header = Parser::<Skip>::new()
        .read_header(&mut reader)
        .map_err(unreadable)?;
    let body = bytes.len() as u64 - reader.get_ref().position();
    check_counts(&header, body)?;
    let (mut verts, mut faces) = (None, None);
    for (name, def) in &header.elements {
        match name.as_str() {
            "vertex" => {
                verts = Some(
                    Parser::<Vertex>::new()
                        .read_payload_for_element(&mut reader, def, &header)
                        .map_err(unreadable)?,
                )
            }
            "face" => {
                faces = Some(
                    Parser::<Face>::new()
                        .read_payload_for_element(&mut reader, def, &header)
                        .map_err(unreadable)?,
                )
            }
            _ => {
                Parser::<Skip>::new()
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(unreadable)?;
            }
        }
    }
    let (Some(vdef), Some(verts)) = (header.elements.get("vertex"), verts) else {
        return Err("no `vertex` element".into());
    };
    let Some(faces) = faces else {
        return Err("no `face` element".into());
    };
    let mut m = vertices(vdef, &verts)?;
    drop(verts);
    m.tris = triangles(&faces)?;
    Ok(m)
}

/// Refuse a header whose elements need more bytes than follow it (a file
/// truncated, or lying about its counts), or that declares entries of an
/// element without properties: ply-rs would make a record for each from no
/// bytes at all, a billion of them if the header says so.
fn check_counts(header: &Header, body: u64) -> Result<(), String> {
    let ascii = matches!(header.encoding, Encoding::Ascii);
    let mut need: u128 = 0;
    for (name, e) in &header.elements {
        if e.count > 0 && e.properties.is_empty() {
            return Err(format!(
                "the header declares {} `{name}` elements but no property for them",
                e.count
            ));
        }
        let per: u128 = e
            .properties
            .values()
            .map(|p| min_bytes(&p.data_type, ascii))
            .sum();
        need += per * e.count as u128;
        // An ASCII file's last line may lack its line break.
        if need > body as u128 + u128::from(ascii) {
            return Err(format!(
                "the header declares {} `{name}` elements, which need at least {need} bytes, but {body} bytes follow the header: the file is truncated or its counts are wrong",
                e.count
            ));
        }
    }
    Ok(())
}

/// The fewest bytes a property takes: its binary size (a list, its count),
/// or in ASCII a digit and a separator.
fn min_bytes(t: &PropertyType, ascii: bool) -> u128 {
    if ascii {
        return 2;
    }
    let size = |s: &ScalarType| match s {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    };
    match t {
        PropertyType::Scalar(s) => size(s),
        PropertyType::List(count, _) => size(count),
    }
}

/// Positions, and normals and texture coordinates when the header has them.
fn vertices(def: &ElementDef, verts: &[Vertex]) -> Result<MeshData, String> {
    let has = |slot: usize| def.properties.contains_key(SLOTS[slot]);
    let uv = UV_PAIRS.iter().copied().find(|&(a, b)| has(a) && has(b));
    let mut m = MeshData {
        positions: Vec::with_capacity(verts.len()),
        tris: Vec::new(),
        normals: has(3).then(|| Vec::with_capacity(verts.len())),
        uvs: uv.map(|_| Vec::with_capacity(verts.len())),
    };
    for (i, v) in verts.iter().enumerate() {
        let g = |slot: usize| match v.has & (1 << slot) {
            0 => Err(format!(
                "vertex {i}: missing or non-numeric `{}`",
                SLOTS[slot]
            )),
            _ => Ok(v.v[slot]),
        };
        m.positions.push([g(0)?, g(1)?, g(2)?]);
        if let Some(ns) = &mut m.normals {
            ns.push([g(3)?, g(4)?, g(5)?]);
        }
        if let (Some(us), Some((a, b))) = (&mut m.uvs, uv) {
            us.push([g(a)?, g(b)?]);
        }
    }
    Ok(m)
}

/// The faces fan-triangulated; faces of fewer than three vertices refused.
fn triangles(faces: &[Face]) -> Result<Vec<[u32; 3]>, String> {
    let mut tris = Vec::with_capacity(faces.len());
    for (i, f) in faces.iter().enumerate() {
        if !f.has {
            return Err(format!("face {i}: missing `vertex_indices` list"));
        }
        if let Some(b) = f.bad {
            return Err(format!(
                "face {i} has the vertex index {b}, which cannot be one"
            ));
        }
        if f.count < 3 {
            return Err(format!(
                "face {i} has {} vertices; a face needs at least 3",
                f.count
            ));
        }
        let idx = |k: usize| if k < 3 { f.first[k] } else { f.rest[k - 3] };
        for k in 1..f.count - 1 {
            tris.push([idx(0), idx(k), idx(k + 1)]);
        }
    }
    Ok(tris)
}
