//! The ray sets of the Embree anchor (`../shared/anchors/embree/RAYS.md`),
//! generated bit for bit as specified there, and the binary ray and hit file
//! formats of `rtk trace` (docs/trace.md).
//!
//! The generators follow the specification's arithmetic exactly: f64, no
//! fused multiply-add (Rust never contracts `a * b + c`), the operations in
//! the order written, only the final origin and direction rounded to f32.

use anyhow::{bail, Context, Result};
use std::path::Path;

/// A ray as the files and generators hold it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayRec {
    /// Origin.
    pub o: [f32; 3],
    /// Direction.
    pub d: [f32; 3],
    /// Open interval of accepted hits.
    pub t_min: f32,
    /// Open interval's upper end.
    pub t_max: f32,
}

/// A hit as the hit file holds it: `t` (+inf on a miss), primitive id (the
/// id within the object hit; `u32::MAX` on a miss), barycentrics u, v.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HitRec {
    /// Distance along the ray.
    pub t: f32,
    /// Primitive id.
    pub prim: u32,
    /// Barycentric weight of vertex 1.
    pub u: f32,
    /// Barycentric weight of vertex 2.
    pub v: f32,
}

impl RayRec {
    /// What `rtk trace` accepts: a finite origin and direction, t_min >= 0
    /// and t_max >= t_min (a NaN t_max is refused, an infinite one not).
    #[inline]
    pub fn is_valid(&self) -> bool {
        self.o.iter().chain(self.d.iter()).all(|x| x.is_finite())
            && self.t_min >= 0.0
            && !(self.t_max < self.t_min)
            && !self.t_max.is_nan()
    }
}

impl HitRec {
    /// A miss: `t` +inf, no primitive.
    pub const MISS: HitRec = HitRec {
        t: f32::INFINITY,
        prim: u32::MAX,
        u: 0.0,
        v: 0.0,
    };
}

/// The specification's random number generator.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / 9007199254740992.0)
    }
}

fn ray(o: [f32; 3], d: [f32; 3]) -> RayRec {
    RayRec {
        o,
        d,
        t_min: 0.0,
        t_max: f32::INFINITY,
    }
}

/// "primary": 1024x1024 pinhole rays through pixel centres (RAYS.md §2).
pub fn primary(lo: [f64; 3], hi: [f64; 3]) -> Vec<RayRec> {
    const W: u32 = 1024;
    const H: u32 = 1024;
    const TAN_HALF_FOV: f64 = 0.5;
    let mut c = [0.0; 3];
    let mut e = [0.0; 3];
    for i in 0..3 {
        c[i] = (lo[i] + hi[i]) * 0.5;
        e[i] = hi[i] - lo[i];
    }
    let radius = 0.5 * (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
    let dist = 1.5 * radius;
    let dl = 6.0f64.sqrt();
    let d_eye = [1.0 / dl, 1.0 / dl, 2.0 / dl];
    let mut eye = [0.0; 3];
    let mut w = [0.0; 3];
    for i in 0..3 {
        eye[i] = c[i] + d_eye[i] * dist;
        w[i] = -d_eye[i];
    }
    let ul = (w[2] * w[2] + w[0] * w[0]).sqrt();
    let u = [-w[2] / ul, 0.0, w[0] / ul];
    let v = [
        u[1] * w[2] - u[2] * w[1],
        u[2] * w[0] - u[0] * w[2],
        u[0] * w[1] - u[1] * w[0],
    ];
    let eye32 = [eye[0] as f32, eye[1] as f32, eye[2] as f32];
    let mut rays = Vec::with_capacity((W * H) as usize);
    for py in 0..H {
        let sy = (1.0 - 2.0 * (py as f64 + 0.5) / H as f64) * TAN_HALF_FOV;
        for px in 0..W {
            let sx = (2.0 * (px as f64 + 0.5) / W as f64 - 1.0) * TAN_HALF_FOV;
            let mut d = [0.0; 3];
            for i in 0..3 {
                d[i] = w[i] + sx * u[i] + sy * v[i];
            }
            let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            rays.push(ray(
                eye32,
                [(d[0] / l) as f32, (d[1] / l) as f32, (d[2] / l) as f32],
            ));
        }
    }
    rays
}

/// "incoherent": 2^20 rays from the padded box's surface, uniform inward
/// directions, one splitmix64 stream with seed 12345 (RAYS.md §3).
pub fn incoherent(lo: [f64; 3], hi: [f64; 3]) -> Vec<RayRec> {
    const N: usize = 1 << 20;
    let mut e = [0.0; 3];
    for i in 0..3 {
        e[i] = hi[i] - lo[i];
    }
    let pad = 0.01 * (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
    let (mut bl, mut bh, mut be) = ([0.0; 3], [0.0; 3], [0.0; 3]);
    for i in 0..3 {
        bl[i] = lo[i] - pad;
        bh[i] = hi[i] + pad;
        be[i] = bh[i] - bl[i];
    }
    let area = [be[1] * be[2], be[0] * be[2], be[0] * be[1]];
    let area_sum = area[0] + area[1] + area[2];
    let mut rng = SplitMix64(12345);
    let mut rays = Vec::with_capacity(N);
    for _ in 0..N {
        let t = rng.next_f64() * area_sum;
        let ax = if t < area[0] {
            0
        } else if t < area[0] + area[1] {
            1
        } else {
            2
        };
        let side = rng.next_u64() >> 63;
        let (a1, a2) = match ax {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        let mut o = [0.0; 3];
        o[a1] = bl[a1] + rng.next_f64() * be[a1];
        o[a2] = bl[a2] + rng.next_f64() * be[a2];
        o[ax] = if side == 1 { bh[ax] } else { bl[ax] };
        let (x, y, z, l2) = loop {
            let x = 2.0 * rng.next_f64() - 1.0;
            let y = 2.0 * rng.next_f64() - 1.0;
            let z = 2.0 * rng.next_f64() - 1.0;
            let l2 = x * x + y * y + z * z;
            if l2 > 1e-6 && l2 <= 1.0 {
                break (x, y, z, l2);
            }
        };
        let l = l2.sqrt();
        let mut d = [x / l, y / l, z / l];
        if (side == 0 && d[ax] < 0.0) || (side == 1 && d[ax] > 0.0) {
            d = [-d[0], -d[1], -d[2]];
        }
        rays.push(ray(
            [o[0] as f32, o[1] as f32, o[2] as f32],
            [d[0] as f32, d[1] as f32, d[2] as f32],
        ));
    }
    rays
}

/// RAYS.md's `rays_hash`: FNV-1a 64 over the rays' origin and direction bytes.
pub fn rays_hash(rays: &[RayRec]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for r in rays {
        for v in r.o.iter().chain(r.d.iter()) {
            for b in v.to_le_bytes() {
                h ^= b as u64;
                h = h.wrapping_mul(0x100_0000_01b3);
            }
        }
    }
    h
}

/// Bytes per ray in a ray file.
pub const RAY_BYTES: usize = 32;
/// Bytes per hit in a hit file.
pub const HIT_BYTES: usize = 16;

/// Largest ray file read: 2^27 rays (4 GiB). Like scenes and meshes, a ray
/// file must be a regular file (a FIFO would block, `/dev/zero` never end).
pub const MAX_RAY_FILE_BYTES: u64 = (RAY_BYTES as u64) << 27;

/// Read a ray file: per ray, little-endian f32 `ox oy oz dx dy dz t_min t_max`.
pub fn read_rays(path: &Path) -> Result<Vec<RayRec>> {
    let bytes = rtk_shell::file::read_regular_file(path, MAX_RAY_FILE_BYTES, "ray file")
        .map_err(|m| anyhow::anyhow!("{}: {m}", path.display()))?;
    parse_rays(path, &bytes)
}

/// A ray file's bytes (`path` names it in messages): what [`read_rays`]
/// does once the file is read, and what the fuzz targets call.
pub(crate) fn parse_rays(path: &Path, bytes: &[u8]) -> Result<Vec<RayRec>> {
    if !bytes.len().is_multiple_of(RAY_BYTES) {
        bail!(
            "{}: {} bytes is not a whole number of {RAY_BYTES}-byte rays (ox oy oz dx dy dz t_min t_max, little-endian f32)",
            path.display(),
            bytes.len()
        );
    }
    let f = |c: &[u8], k: usize| {
        f32::from_le_bytes([c[4 * k], c[4 * k + 1], c[4 * k + 2], c[4 * k + 3]])
    };
    let rays: Vec<RayRec> = bytes
        .chunks_exact(RAY_BYTES)
        .map(|c| RayRec {
            o: [f(c, 0), f(c, 1), f(c, 2)],
            d: [f(c, 3), f(c, 4), f(c, 5)],
            t_min: f(c, 6),
            t_max: f(c, 7),
        })
        .collect();
    if let Some((i, _)) = rays.iter().enumerate().find(|(_, r)| !r.is_valid()) {
        bail!(
            "{}: ray {i} has a non-finite origin or direction, or t_min < 0 or t_max < t_min",
            path.display()
        );
    }
    Ok(rays)
}

/// Write a ray file (the format of [`read_rays`]).
pub fn write_rays(path: &Path, rays: &[RayRec]) -> Result<()> {
    let mut out = Vec::with_capacity(rays.len() * RAY_BYTES);
    for r in rays {
        for v in
            r.o.iter()
                .chain(r.d.iter())
                .chain([r.t_min, r.t_max].iter())
        {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    std::fs::write(path, out).with_context(|| format!("writing rays to {}", path.display()))
}

/// Hits as a hit file's bytes: per ray, little-endian `t` (f32), `prim`
/// (u32), `u`, `v` (f32).
pub fn hit_bytes(hits: &[HitRec]) -> Vec<u8> {
    let mut out = Vec::with_capacity(hits.len() * HIT_BYTES);
    for h in hits {
        out.extend_from_slice(&h.t.to_le_bytes());
        out.extend_from_slice(&h.prim.to_le_bytes());
        out.extend_from_slice(&h.u.to_le_bytes());
        out.extend_from_slice(&h.v.to_le_bytes());
    }
    out
}

#[cfg(test)]
#[allow(clippy::excessive_precision)] // RAYS.md's figures, printed with %.9g
mod tests {
    use super::*;

    /// RAYS.md's reference values for the bunny (its bbox, as f32 widened).
    const BUNNY_LO: [f64; 3] = [
        -4.958_475_11_f32 as f64,
        -0.003_149_f32 as f64,
        -3.729_832_89_f32 as f64,
    ];
    const BUNNY_HI: [f64; 3] = [
        4.948_850_15_f32 as f64,
        9.654_747_96_f32 as f64,
        3.810_638_9_f32 as f64,
    ];

    #[test]
    fn primary_rays_match_the_specification() {
        let r = primary(BUNNY_LO, BUNNY_HI);
        assert_eq!(r.len(), 1 << 20);
        assert_eq!(r[0].d, [-0.772_839_427, 0.038_993_407, -0.633_402_526]);
        assert_eq!(format!("{:016x}", rays_hash(&r)), "b00145327fe5a943");
    }

    #[test]
    fn incoherent_rays_match_the_specification() {
        let r = incoherent(BUNNY_LO, BUNNY_HI);
        assert_eq!(r[0].o, [-5.116_046_91, 1.031_482_22, -2.503_890_99]);
        assert_eq!(format!("{:016x}", rays_hash(&r)), "33fcf27827eb0eac");
    }

    #[test]
    fn ray_files_round_trip() {
        let dir = std::env::temp_dir().join(format!("rtk-rays-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("r.bin");
        let rays = vec![RayRec {
            o: [1.0, 2.0, 3.0],
            d: [0.0, 0.0, -1.0],
            t_min: 0.5,
            t_max: 9.0,
        }];
        write_rays(&p, &rays).unwrap();
        assert_eq!(read_rays(&p).unwrap(), rays);
        std::fs::write(&p, [0u8; 31]).unwrap();
        assert!(read_rays(&p)
            .unwrap_err()
            .to_string()
            .contains("whole number"));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
