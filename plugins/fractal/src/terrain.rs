//! The heightfield: diamond-square midpoint displacement on a
//! (2^levels + 1)² grid, one random number per vertex drawn from its own
//! stream (seed, vertex index), so the result depends on the parameters alone.

use rtk_kernel::glam::Vec3;
use rtk_kernel::{Bounds3, Prepare, RngState};

/// Largest `levels`: 2^11 + 1 = 2049 vertices a side, 8.4 M triangles (about
/// 0.8 GB with the aggregate built over them). Level 12 would take 3 GB.
pub const MAX_LEVELS: u32 = 11;

/// What the landscape is generated from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TerrainSpec {
    pub seed: u64,
    pub size: [f64; 2],
    pub levels: u32,
    pub height: f64,
    pub roughness: f64,
    /// World position of the middle of the extent at height 0.
    pub center: [f64; 3],
    /// The renderer's origin (`Env::origin`), subtracted in f64.
    pub origin: [f64; 3],
}

/// One grid row's vertices and the triangles of the cells above it.
type Row<'a> = (&'a mut [[f32; 3]], &'a mut [[u32; 3]]);

/// The generated grid.
#[derive(Default, Debug, PartialEq)]
pub struct Terrain {
    /// Vertices a side.
    pub n: u32,
    pub positions: Vec<[f32; 3]>,
    pub tris: Vec<[u32; 3]>,
}

/// Uniform in [-1, 1), from the vertex's own stream.
#[inline]
fn noise(seed: u64, k: usize) -> f64 {
    RngState::for_sample(seed, k as u64, 0x6672_6163).next_f64() * 2.0 - 1.0
}

/// Heights in [0, 1] (the lowest vertex at 0, the highest at 1) by the
/// diamond-square algorithm (Fournier, Fussell and Carpenter 1982; Miller
/// 1986): the displacement's amplitude falls by 2^-H per level.
pub fn heights(seed: u64, levels: u32, roughness: f64) -> Vec<f64> {
    let n = (1usize << levels) + 1;
    let mut h = vec![0.0f64; n * n];
    let at = |i: usize, j: usize| j * n + i;
    let mut amp = 1.0f64;
    for &(i, j) in &[(0, 0), (n - 1, 0), (0, n - 1), (n - 1, n - 1)] {
        h[at(i, j)] = noise(seed, at(i, j)) * amp;
    }
    let falloff = (-roughness).exp2();
    let mut s = n - 1;
    while s > 1 {
        let half = s / 2;
        amp *= falloff;
        // Diamond step: the centre of each square.
        for j in (half..n).step_by(s) {
            for i in (half..n).step_by(s) {
                let avg = 0.25
                    * (h[at(i - half, j - half)]
                        + h[at(i + half, j - half)]
                        + h[at(i - half, j + half)]
                        + h[at(i + half, j + half)]);
                h[at(i, j)] = avg + noise(seed, at(i, j)) * amp;
            }
        }
        // Square step: the middle of each edge, from its 3 or 4 neighbours.
        for j in (0..n).step_by(half) {
            let first = if (j / half).is_multiple_of(2) {
                half
            } else {
                0
            };
            for i in (first..n).step_by(s) {
                let (mut sum, mut cnt) = (0.0, 0.0);
                if i >= half {
                    sum += h[at(i - half, j)];
                    cnt += 1.0;
                }
                if i + half < n {
                    sum += h[at(i + half, j)];
                    cnt += 1.0;
                }
                if j >= half {
                    sum += h[at(i, j - half)];
                    cnt += 1.0;
                }
                if j + half < n {
                    sum += h[at(i, j + half)];
                    cnt += 1.0;
                }
                h[at(i, j)] = sum / cnt + noise(seed, at(i, j)) * amp;
            }
        }
        s = half;
    }
    let (lo, hi) = h
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    let range = hi - lo;
    if range > 0.0 {
        for x in &mut h {
            *x = (*x - lo) / range;
        }
    } else {
        h.fill(0.0);
    }
    h
}

impl Terrain {
    /// Build the grid: vertex (i, j) at x = centre + (i/(n−1) − ½)·size[0],
    /// z likewise with j and size[1], y = centre + height·h(i, j), computed
    /// in f64 relative to the renderer's origin and rounded once.
    pub fn generate(spec: &TerrainSpec, env: Option<&Prepare>) -> Terrain {
        let h = heights(spec.seed, spec.levels, spec.roughness);
        let n = (1usize << spec.levels) + 1;
        let c: [f64; 3] = std::array::from_fn(|k| spec.center[k] - spec.origin[k]);
        let step = [spec.size[0] / (n - 1) as f64, spec.size[1] / (n - 1) as f64];
        let vertex = |k: usize| -> [f32; 3] {
            let (i, j) = (k % n, k / n);
            [
                (c[0] + (i as f64 * step[0] - 0.5 * spec.size[0])) as f32,
                (c[1] + spec.height * h[k]) as f32,
                (c[2] + (j as f64 * step[1] - 0.5 * spec.size[1])) as f32,
            ]
        };
        let m = n - 1;
        let cell = |q: usize| -> [[u32; 3]; 2] {
            let (i, j) = (q % m, q / m);
            let v00 = (j * n + i) as u32;
            let v10 = v00 + 1;
            let v01 = v00 + n as u32;
            let v11 = v01 + 1;
            // Both wound so that the normal points up (+y).
            [[v00, v01, v10], [v10, v01, v11]]
        };
        let mut positions = vec![[0.0f32; 3]; n * n];
        let mut tris = vec![[0u32; 3]; 2 * m * m];
        match env {
            // Rows in parallel on the host's pool: each task owns its rows.
            Some(env) if n >= 257 => {
                let rows: Vec<std::sync::Mutex<Row>> = positions
                    .chunks_mut(n)
                    .zip(tris.chunks_mut(2 * m).chain(std::iter::once(&mut [][..])))
                    .map(std::sync::Mutex::new)
                    .collect();
                env.parallel_for(n as u64, |j| {
                    let j = j as usize;
                    let mut g = rows[j].lock().unwrap_or_else(|e| e.into_inner());
                    let (p, t) = &mut *g;
                    for (i, v) in p.iter_mut().enumerate() {
                        *v = vertex(j * n + i);
                    }
                    for (q, pair) in t.chunks_mut(2).enumerate() {
                        pair.copy_from_slice(&cell(j * m + q));
                    }
                });
            }
            _ => {
                for (k, v) in positions.iter_mut().enumerate() {
                    *v = vertex(k);
                }
                for (q, pair) in tris.chunks_mut(2).enumerate() {
                    pair.copy_from_slice(&cell(q));
                }
            }
        }
        Terrain {
            n: n as u32,
            positions,
            tris,
        }
    }

    /// Texture coordinates of vertex `k`: (i, j) / (n − 1), over the extent.
    #[inline]
    pub fn uv(&self, k: u32) -> [f32; 2] {
        let m = (self.n - 1) as f32;
        [(k % self.n) as f32 / m, (k / self.n) as f32 / m]
    }

    pub fn bounds(&self) -> Bounds3 {
        self.positions
            .iter()
            .fold(Bounds3::EMPTY, |b, &p| b.include(p.into()))
    }

    /// Area-weighted vertex normals.
    pub fn vertex_normals(&self) -> Vec<Vec3> {
        let mut nrm = vec![Vec3::ZERO; self.positions.len()];
        for t in &self.tris {
            let [a, b, c] = t.map(|k| Vec3::from(self.positions[k as usize]));
            let f = (b - a).cross(c - a);
            for &v in t {
                nrm[v as usize] += f;
            }
        }
        nrm.into_iter().map(|v| v.normalize_or(Vec3::Y)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(seed: u64, levels: u32) -> TerrainSpec {
        TerrainSpec {
            seed,
            size: [10.0, 8.0],
            levels,
            height: 2.0,
            roughness: 0.7,
            center: [1.0, -0.5, 3.0],
            origin: [0.0; 3],
        }
    }

    #[test]
    fn deterministic_for_a_seed() {
        let a = Terrain::generate(&spec(7, 6), None);
        let b = Terrain::generate(&spec(7, 6), None);
        assert_eq!(a, b);
        let c = Terrain::generate(&spec(8, 6), None);
        assert_ne!(a.positions, c.positions, "another seed, another landscape");
        assert_eq!(a.tris.len(), 2 * 64 * 64);
        assert_eq!(a.positions.len(), 65 * 65);
    }

    #[test]
    fn heights_span_zero_to_height_and_bounds_contain_every_vertex() {
        let t = Terrain::generate(&spec(3, 7), None);
        let b = t.bounds();
        let (lo3, hi3) = ([b.min.x, b.min.y, b.min.z], [b.max.x, b.max.y, b.max.z]);
        for p in &t.positions {
            for k in 0..3 {
                assert!(lo3[k] <= p[k] && p[k] <= hi3[k]);
            }
        }
        let ys: Vec<f32> = t.positions.iter().map(|p| p[1]).collect();
        let lo = ys.iter().cloned().fold(f32::INFINITY, f32::min);
        let hi = ys.iter().cloned().fold(f32::NEG_INFINITY, f32::max);
        assert_eq!(lo, -0.5);
        assert!((hi - 1.5).abs() < 1e-6, "{hi}");
        // The extent: x over [1 - 5, 1 + 5], z over [3 - 4, 3 + 4].
        assert_eq!(lo3[0], -4.0);
        assert_eq!(hi3[0], 6.0);
        assert_eq!(lo3[2], -1.0);
        assert_eq!(hi3[2], 7.0);
    }

    #[test]
    fn every_triangle_faces_up_and_the_origin_is_subtracted() {
        let t = Terrain::generate(&spec(5, 5), None);
        for tri in &t.tris {
            let [a, b, c] = tri.map(|k| Vec3::from(t.positions[k as usize]));
            assert!((b - a).cross(c - a).y > 0.0);
        }
        let mut s = spec(5, 5);
        s.origin = [1.0, -0.5, 3.0];
        s.center = [1.0, -0.5, 3.0];
        let moved = Terrain::generate(&s, None);
        let mut s0 = spec(5, 5);
        s0.center = [0.0; 3];
        assert_eq!(moved, Terrain::generate(&s0, None));
    }
}
