//! The interior of a closed triangle mesh: the paper's "in interior" for
//! objects made of triangles (`mesh`, and any primitive that lends them).
//!
//! A mesh has an interior when it is closed: after welding vertices at the
//! same position, every edge is shared by exactly two triangles that cross
//! it in opposite directions (a consistently oriented 2-manifold). An open
//! mesh answers that it has none rather than guessing.
//!
//! A point is inside when rays from it cross the surface an odd number of
//! times. The crossings are counted with the kernel's watertight test, so no
//! ray slips between two triangles; a ray that runs exactly through an edge
//! or a vertex may count it twice, so three rays in unrelated directions
//! vote and the majority answers. Points closer to the surface than the
//! test's error bound may be answered either way (the `in_interior`
//! contract); farther ones are answered as every ray's parity says.
//!
//! Why parity rather than the generalised winding number (Jacobson et al.
//! 2013): the winding number needs every triangle for every point, or a
//! hierarchy of dipole approximations whose error must then be bounded;
//! parity needs only the rays' crossings, found through a BVH, and is exact
//! wherever the watertight test is.

use crate::{BuildParams, Bvh4};
use rtk_abi::{Bounds3, Ray};
use rtk_geom::intersect_triangle;
use std::collections::HashMap;

/// Three directions with no symmetry in common with axis-aligned or
/// regularly tessellated meshes (unit, from an irrational rotation).
const VOTERS: [[f32; 3]; 3] = [
    [0.546_307, 0.718_221, 0.430_850],
    [-0.691_283, 0.182_137, 0.699_155],
    [0.214_089, -0.887_307, 0.408_428],
];

/// A closed triangle mesh, ready to answer whether a point is inside.
pub struct TriangleSolid {
    tris: Vec<[[f32; 3]; 3]>,
    bvh: Bvh4,
    /// For each leaf, by its first entry in `bvh.order`: one past its last.
    leaf_end: Vec<u32>,
}

impl TriangleSolid {
    /// The solid the triangles bound, or `None` when they do not close a
    /// volume (see the module doc). Triangle `i` has the vertices
    /// `positions[indices[i][k]]`, counter-clockwise seen from outside (or
    /// clockwise: parity does not care, but it must be consistent).
    pub fn new(positions: &[[f32; 3]], indices: &[[u32; 3]]) -> Option<TriangleSolid> {
        if indices.is_empty() || !closed(positions, indices) {
            return None;
        }
        let tris: Vec<[[f32; 3]; 3]> = indices
            .iter()
            .map(|t| t.map(|i| positions[i as usize]))
            .collect();
        let boxes: Vec<Bounds3> = tris.iter().map(crate::tri_bounds).collect();
        let bvh = Bvh4::build(&boxes, BuildParams::default());
        let mut leaf_end = vec![0; bvh.order.len()];
        for r in bvh.leaves() {
            if r.start < leaf_end.len() {
                leaf_end[r.start] = r.end as u32;
            }
        }
        Some(TriangleSolid {
            tris,
            bvh,
            leaf_end,
        })
    }

    /// Is `p` inside: the majority of three rays' parities.
    pub fn contains(&self, p: [f32; 3]) -> bool {
        let odd = VOTERS
            .iter()
            .filter(|d| self.crossings(p, **d) % 2 == 1)
            .count();
        odd >= 2
    }

    /// How many times the ray from `p` along `d` crosses the surface.
    fn crossings(&self, p: [f32; 3], d: [f32; 3]) -> u32 {
        let ray = Ray::new(p.into(), d.into());
        let mut count = 0u32;
        let mut node_tests = 0u64;
        self.bvh
            .traverse_any(&ray, f32::INFINITY, &mut node_tests, |first: usize| {
                let end = self.leaf_end.get(first).copied().unwrap_or(0) as usize;
                for &i in &self.bvh.order[first..end.max(first)] {
                    if intersect_triangle(p, d, self.tris[i as usize], 0.0, f32::INFINITY).is_some()
                    {
                        count += 1;
                    }
                }
                Some(f32::INFINITY)
            });
        count
    }
}

/// Whether every edge, after welding vertices at equal positions, is
/// crossed once in each direction by the triangles that share it.
fn closed(positions: &[[f32; 3]], indices: &[[u32; 3]]) -> bool {
    let mut canon: HashMap<[u32; 3], u32> = HashMap::new();
    let weld: Vec<u32> = positions
        .iter()
        .enumerate()
        .map(|(i, p)| *canon.entry(p.map(f32::to_bits)).or_insert(i as u32))
        .collect();
    let mut edges: HashMap<(u32, u32), u32> = HashMap::with_capacity(indices.len() * 3);
    for t in indices {
        let v = t.map(|i| weld.get(i as usize).copied().unwrap_or(u32::MAX));
        for k in 0..3 {
            let (a, b) = (v[k], v[(k + 1) % 3]);
            if a == b {
                return false; // a degenerate edge bounds nothing
            }
            *edges.entry((a, b)).or_insert(0) += 1;
        }
    }
    edges
        .iter()
        .all(|(&(a, b), &n)| n == 1 && edges.get(&(b, a)) == Some(&1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rtk_abi::RngState;

    /// The unit cube [0, 1]³, outward, as 12 triangles.
    fn cube() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        let p: Vec<[f32; 3]> = (0..8)
            .map(|i| [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32])
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let t = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        (p, t)
    }

    #[test]
    fn a_cube_is_closed_and_answers_inside_and_outside() {
        let (p, t) = cube();
        let s = TriangleSolid::new(&p, &t).expect("closed");
        assert!(s.contains([0.5, 0.5, 0.5]));
        assert!(s.contains([0.01, 0.99, 0.5]));
        assert!(!s.contains([1.5, 0.5, 0.5]));
        assert!(!s.contains([-0.01, 0.5, 0.5]));
    }

    #[test]
    fn an_open_or_inconsistent_mesh_has_no_interior() {
        let (p, mut t) = cube();
        t.pop();
        assert!(TriangleSolid::new(&p, &t).is_none(), "a missing triangle");
        let (p, mut t) = cube();
        t[0].swap(1, 2);
        assert!(TriangleSolid::new(&p, &t).is_none(), "one flipped triangle");
    }

    #[test]
    fn duplicated_vertices_are_welded() {
        let (p, t) = cube();
        // Every triangle with vertices of its own (as a PLY with seams has).
        let p2: Vec<[f32; 3]> = t
            .iter()
            .flat_map(|tri| tri.map(|i| p[i as usize]))
            .collect();
        let t2: Vec<[u32; 3]> = (0..t.len() as u32)
            .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
            .collect();
        let s = TriangleSolid::new(&p2, &t2).expect("closed after welding");
        assert!(s.contains([0.3, 0.6, 0.2]));
    }

    #[test]
    fn random_points_agree_with_the_box() {
        let (p, t) = cube();
        let s = TriangleSolid::new(&p, &t).unwrap();
        let mut rng = RngState::seeded(4);
        for _ in 0..10_000 {
            let q = [0; 3].map(|_| rng.range_f32(-0.5, 1.5));
            let margin = q
                .iter()
                .map(|x| x.abs().min((x - 1.0).abs()))
                .fold(f32::MAX, f32::min);
            if margin < 1e-5 {
                continue;
            }
            let inside = q.iter().all(|x| (0.0..1.0).contains(x));
            assert_eq!(s.contains(q), inside, "{q:?}");
        }
    }
}
