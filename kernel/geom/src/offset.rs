//! Spawning rays from surfaces: offset past the error bound along the
//! geometric normal (pbrt-v4 `OffsetRayOrigin`), never a scene epsilon.

use glam::Vec3;
use rtk_abi::{LocalGeom, Ray};

/// Move `p` past its error box `p_err` along the geometric normal `n`, to the
/// side `w` points to, then round each component away from `p`.
#[inline]
pub fn offset_ray_origin(p: Vec3, p_err: Vec3, n: Vec3, w: Vec3) -> Vec3 {
    let d = n.abs().dot(p_err);
    let mut offset = n * d;
    if w.dot(n) < 0.0 {
        offset = -offset;
    }
    let mut po = p + offset;
    for i in 0..3 {
        if offset[i] != 0.0 {
            po[i] = ulp_away(po[i], offset[i] > 0.0);
        }
    }
    po
}

/// `x` moved one float towards +∞ (`up`) or −∞: `next_up`/`next_down` for
/// the finite values a hit point has (positions are validated, rule 1),
/// without their NaN and infinity branches (this runs for every spawned
/// ray). At ±0 it steps to the smallest subnormal of the right sign.
#[inline]
fn ulp_away(x: f32, up: bool) -> f32 {
    if x == 0.0 {
        let tiny = f32::from_bits(1);
        return if up { tiny } else { -tiny };
    }
    let b = x.to_bits();
    // Away from zero grows the magnitude's bits; towards zero shrinks them.
    f32::from_bits(if (x > 0.0) == up { b + 1 } else { b - 1 })
}

/// A ray leaving the surface at `g` in direction `dir`, one generation deeper.
#[inline]
pub fn spawn_ray(g: &LocalGeom, dir: Vec3, parent: &Ray) -> Ray {
    let o = offset_ray_origin(g.p.v(), g.p_err.v(), g.ng.v(), dir);
    Ray {
        origin: o.into(),
        dir: dir.into(),
        t_min: 0.0,
        t_max: f32::INFINITY,
        time: parent.time,
        generation: parent.generation + 1,
    }
}

/// Fraction of the segment a point-to-point shadow ray stops short of its end
/// (pbrt's ShadowEpsilon), so that the target surface is not reported.
pub const SHADOW_EPSILON: f32 = 1e-4;

/// A shadow ray from the surface at `g` towards the point `to` (unnormalised
/// direction, `t_max = 1 - SHADOW_EPSILON`).
#[inline]
pub fn spawn_ray_to(g: &LocalGeom, to: Vec3, parent: &Ray) -> Ray {
    let o = offset_ray_origin(g.p.v(), g.p_err.v(), g.ng.v(), to - g.p.v());
    Ray {
        origin: o.into(),
        dir: (to - o).into(),
        t_min: 0.0,
        t_max: 1.0 - SHADOW_EPSILON,
        time: parent.time,
        generation: parent.generation + 1,
    }
}

/// A shadow ray between two surface points, each end offset past its own
/// error bound towards the other (pbrt-v4 `SpawnRayTo` between
/// interactions), stopping `SHADOW_EPSILON` short of the far end.
///
/// Why both ends: offsetting only the origin leaves the far end inside the
/// target's error box, and the target surface then occludes its own point
/// (numerics.md S4) — a light leak or a false shadow between two faces of
/// the same enclosure.
#[inline]
pub fn spawn_ray_between(from: &LocalGeom, to: &LocalGeom, parent: &Ray) -> Ray {
    let (pf, pt) = (from.p.v(), to.p.v());
    let o = offset_ray_origin(pf, from.p_err.v(), from.ng.v(), pt - pf);
    let end = offset_ray_origin(pt, to.p_err.v(), to.ng.v(), o - pt);
    Ray {
        origin: o.into(),
        dir: (end - o).into(),
        t_min: 0.0,
        t_max: 1.0 - SHADOW_EPSILON,
        time: parent.time,
        generation: parent.generation + 1,
    }
}

#[cfg(test)]
mod ulp_tests {
    use super::ulp_away;

    #[test]
    fn ulp_away_matches_next_up_and_next_down() {
        let xs = [
            0.0f32, -0.0, 1.0, -1.0, 1e-45, -1e-45, 3.0e38, -3.0e38, 559.2, 1e-38,
        ];
        for x in xs {
            assert_eq!(ulp_away(x, true).to_bits(), x.next_up().to_bits(), "{x} up");
            assert_eq!(
                ulp_away(x, false).to_bits(),
                x.next_down().to_bits(),
                "{x} down"
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{
        intersect_sphere, intersect_triangle, nearest_root, sphere_point_and_error,
        triangle_point_and_error,
    };

    fn hemisphere(s: &mut rtk_abi::RngState, n: Vec3) -> Vec3 {
        loop {
            let v = Vec3::new(
                s.next_f32() * 2.0 - 1.0,
                s.next_f32() * 2.0 - 1.0,
                s.next_f32() * 2.0 - 1.0,
            );
            let l = v.length_squared();
            if l > 1e-4 && l <= 1.0 {
                let v = v / l.sqrt();
                return if v.dot(n) < 0.0 { -v } else { v };
            }
        }
    }

    fn geom(p: [f32; 3], e: [f32; 3], n: Vec3) -> LocalGeom {
        LocalGeom {
            p: p.into(),
            p_err: e.into(),
            ng: n.into(),
            ns: n.into(),
            ..LocalGeom::EMPTY
        }
    }

    /// docs/numerics.md S1: rays spawned from triangle hits, over the hemisphere
    /// the incoming ray came from, never re-hit the triangle, at every scale.
    #[test]
    fn no_self_hits_off_triangles() {
        let mut s = rtk_abi::RngState::seeded(21);
        for &(mag, size) in &[
            (1.0f32, 1.0f32),
            (1e3, 1.0),
            (1e5, 1.0),
            (1.0, 1e-3),
            (1e4, 1e2),
        ] {
            let mut rehits = 0;
            for _ in 0..2000 {
                let c = Vec3::new(s.next_f32() - 0.5, s.next_f32() - 0.5, s.next_f32() - 0.5)
                    .normalize()
                    * mag;
                let v: [[f32; 3]; 3] = std::array::from_fn(|_| {
                    (c + Vec3::new(s.next_f32() - 0.5, s.next_f32() - 0.5, s.next_f32() - 0.5)
                        * size)
                        .to_array()
                });
                let (p0, p1, p2) = (Vec3::from(v[0]), Vec3::from(v[1]), Vec3::from(v[2]));
                let n = (p1 - p0).cross(p2 - p0).normalize();
                let target = p0 * 0.3 + p1 * 0.3 + p2 * 0.4;
                let o = target + hemisphere(&mut s, n) * size * 2.0;
                let d = (target - o).normalize();
                let Some(h) = intersect_triangle(o.to_array(), d.to_array(), v, 0.0, f32::INFINITY)
                else {
                    continue;
                };
                let (p, e) = triangle_point_and_error(v, h.b);
                let g = geom(p, e, n);
                let incoming_side = if (-d).dot(n) > 0.0 { n } else { -n };
                let parent = Ray::new(o, d);
                for _ in 0..50 {
                    let r = spawn_ray(&g, hemisphere(&mut s, incoming_side), &parent);
                    if intersect_triangle(
                        r.origin.to_array(),
                        r.dir.to_array(),
                        v,
                        r.t_min,
                        r.t_max,
                    )
                    .is_some()
                    {
                        rehits += 1;
                    }
                }
            }
            assert_eq!(rehits, 0, "|p| = {mag}, size {size}");
        }
    }

    /// The same off spheres: outward rays never re-hit, inward rays reach
    /// the far side (never the near surface at t ~ 0).
    #[test]
    fn no_self_hits_off_spheres() {
        let mut s = rtk_abi::RngState::seeded(5);
        for &(mag, r) in &[
            (0.0f32, 1.0f32),
            (1e3, 1.0),
            (1e4, 10.0),
            (0.0, 1e-3),
            (100.0, 1e-2),
        ] {
            let c = Vec3::new(0.6, -0.8, 0.0) * mag;
            let (mut rehits, mut misses) = (0, 0);
            for _ in 0..2000 {
                let o = c + Vec3::new(s.next_f32() - 0.5, s.next_f32() - 0.5, 2.0) * r * 3.0;
                let d = (c + Vec3::new(s.next_f32() - 0.5, s.next_f32() - 0.5, 0.0) * r - o)
                    .normalize();
                let Some(h) = intersect_sphere(c.to_array(), r, o.to_array(), d.to_array()) else {
                    continue;
                };
                let Some(t) = nearest_root(&h, 0.0, f32::INFINITY) else {
                    continue;
                };
                let (p, e) = sphere_point_and_error(c.to_array(), r, o.to_array(), d.to_array(), t);
                let n = (Vec3::from(p) - c).normalize();
                let g = geom(p, e, n);
                let parent = Ray::new(o, d);
                for k in 0..50 {
                    let out = k % 2 == 0;
                    let dir = hemisphere(&mut s, if out { n } else { -n });
                    let ray = spawn_ray(&g, dir, &parent);
                    let hit = intersect_sphere(
                        c.to_array(),
                        r,
                        ray.origin.to_array(),
                        ray.dir.to_array(),
                    )
                    .and_then(|h| nearest_root(&h, ray.t_min, ray.t_max));
                    match (out, hit) {
                        (true, Some(_)) => rehits += 1,
                        // The far side lies at the chord 2r cos(angle to -n).
                        (false, Some(t)) if t < 0.5 * 2.0 * r * dir.dot(-n) => rehits += 1,
                        (false, None) => misses += 1,
                        _ => {}
                    }
                }
            }
            assert_eq!((rehits, misses), (0, 0), "|c| = {mag}, r = {r}");
        }
    }
}
