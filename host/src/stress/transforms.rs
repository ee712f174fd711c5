//! X1–X3: instance transforms. Nested levels with large translations, near
//! singular scales, and a scene moved far from the origin, traced through
//! the `transform` plugin the shell puts around every transformed instance,
//! against an f64 reference that composes the same steps in f64.

use super::bench::*;
use super::Case;
use anyhow::Result;
use rtk_kernel::abi::{Hit, LocalGeom, Ray};
use rtk_kernel::geom::{intersect_sphere, nearest_root, spawn_ray, sphere_point_and_error};
use rtk_kernel::glam::{DAffine3, DMat3, DVec3};
use rtk_kernel::RngState;

/// docs/numerics.md X1.
pub const X1: Case = Case {
    id: "X1",
    title: "nested transforms, large translations: self-hits, escapes, bounds",
    run: nested_transforms_keep_rays_inside_and_hits_in_bounds,
};

/// docs/numerics.md X2.
pub const X2: Case = Case {
    id: "X2",
    title: "singular, ill-conditioned, near-flat transforms",
    run: bad_transforms_are_refused_and_flat_ones_exact,
};

/// docs/numerics.md X3.
pub const X3: Case = Case {
    id: "X3",
    title: "scene and camera moved far from the origin",
    run: scenes_far_from_the_origin_render_the_same,
};

/// One transform level as the scene gives it: per-axis scale, rotation
/// about an axis, translation, applied in that order.
#[derive(Clone, Copy)]
struct Level {
    scale: DVec3,
    axis: DVec3,
    degrees: f64,
    translate: DVec3,
}

impl Level {
    /// The TOML steps (every number printed so that it reads back exactly).
    fn toml(&self) -> String {
        format!(
            "[{{ scale = {} }}, {{ rotate = {{ axis = {}, angle = {} }} }}, {{ translate = {} }}]",
            vec3(self.scale.to_array()),
            vec3(self.axis.to_array()),
            num(self.degrees),
            vec3(self.translate.to_array())
        )
    }

    /// The same steps composed in f64 here, independently of the shell.
    fn matrix(&self) -> DAffine3 {
        DAffine3::from_translation(self.translate)
            * DAffine3::from_axis_angle(self.axis.normalize(), self.degrees.to_radians())
            * DAffine3::from_scale(self.scale)
    }
}

/// 10^U(lo, hi).
fn log_uniform(rng: &mut RngState, lo: f64, hi: f64) -> f64 {
    10f64.powf(lo + (hi - lo) * rng.next_f64())
}

/// The f64 reference of a sphere (centre 0, radius r, f32 as the plugin
/// holds it) under the object-to-world transform `m`.
struct Ellipsoid {
    m: DAffine3,
    inv: DAffine3,
    r: f64,
}

impl Ellipsoid {
    fn new(m: DAffine3, r: f32) -> Self {
        Ellipsoid {
            m,
            inv: m.inverse(),
            r: r as f64,
        }
    }

    /// The nearest hit of an f32 world ray over its interval, exactly as
    /// the kernel's routine would find it on the exact object-space ray:
    /// (t, world point).
    fn hit(&self, ray: &Ray) -> Option<(f64, DVec3)> {
        let o = self
            .inv
            .transform_point3(ray.origin.v().as_dvec3())
            .to_array();
        let d = self
            .inv
            .transform_vector3(ray.dir.v().as_dvec3())
            .to_array();
        let h = intersect_sphere([0.0; 3], self.r, o, d)?;
        let t = nearest_root(&h, ray.t_min as f64, ray.t_max as f64)?;
        let (p, _) = sphere_point_and_error([0.0; 3], self.r, o, d, t);
        Some((t, self.m.transform_point3(DVec3::from(p))))
    }

    /// A world point's f64 distance from the surface along the normal, and
    /// the outward world normal: the point projects radially (in object
    /// space) to a surface point s, and the distance is measured from the
    /// tangent plane at s. (Object distance over the gradient's length is
    /// not accurate enough: at the rim of a squashed sphere it overstates
    /// the distance 35-fold.)
    fn distance(&self, p: DVec3) -> (f64, DVec3) {
        let q = self.inv.transform_point3(p);
        let n_obj = q.normalize();
        let s = self.m.transform_point3(n_obj * self.r);
        let n = (self.inv.matrix3.transpose() * n_obj).normalize();
        ((p - s).dot(n).abs(), n)
    }
}

/// What a hit through the transforms is checked for.
#[derive(Default)]
struct Checks {
    hits: u64,
    non_finite: u64,
    /// The f64 distance from the surface exceeds what the spawned-ray
    /// offset covers along the normal (rule 7).
    off_surface: u64,
    worst_t: f64,
}

impl Checks {
    fn hit(&mut self, e: &Ellipsoid, ray: &Ray, hit: &Hit, g: &LocalGeom) {
        self.hits += 1;
        if !(hit.t.is_finite() && g.p.is_finite() && g.p_err.is_finite() && g.ng.is_finite()) {
            self.non_finite += 1;
            return;
        }
        let (p, err) = (g.p.v().as_dvec3(), g.p_err.v().as_dvec3());
        if let Some((t, _)) = e.hit(ray) {
            self.worst_t = self.worst_t.max((hit.t as f64 - t).abs() / t);
        }
        let (dist, n) = e.distance(p);
        if dist > n.abs().dot(err) {
            self.off_surface += 1;
        }
    }
}

/// A random chain of four levels, pbrt-v4's `randomTransform` tempered so
/// that the instance stays traceable: each level a random rotation, a
/// uniform scale 10^U(−2, 2) times a per-axis 10^U(−½, ½) (axes within a
/// factor 10 of each other, far inside the condition 1e7 the shell
/// allows), and a translation 10^U(−3, 5) in a random direction (the
/// catalogue's 10^U(−8, 8) puts objects below the f32 spacing of their own
/// position). The sphere's radius is then chosen so that its smallest world
/// semi-axis is 1e-3 of the largest translation any level applies in world
/// units: large next to the rounding of every level (≈1e-7 of it), so that
/// "inside" exists in f32.
fn chain(rng: &mut RngState) -> (Vec<Level>, f32, DAffine3) {
    let levels: Vec<Level> = (0..4)
        .map(|_| {
            let s = log_uniform(rng, -2.0, 2.0);
            Level {
                scale: DVec3::new(
                    s * log_uniform(rng, -0.5, 0.5),
                    s * log_uniform(rng, -0.5, 0.5),
                    s * log_uniform(rng, -0.5, 0.5),
                ),
                axis: unit_vector(rng),
                degrees: 360.0 * rng.next_f64(),
                translate: unit_vector(rng) * log_uniform(rng, -3.0, 5.0),
            }
        })
        .collect();
    // levels[0] is the outermost.
    let mut m = DAffine3::IDENTITY;
    let mut reach = 1.0f64;
    for l in &levels {
        reach = reach.max((m.matrix3 * l.translate).length());
        m *= l.matrix();
    }
    let smallest = smallest_singular_value(m.matrix3);
    // Within the sphere plugin's radius range.
    let r = (1e-3 * reach / smallest).clamp(1e-3, 1e11) as f32;
    (levels, r, m)
}

/// A lower bound on σ_min of a 3x3 matrix: σ_min = 1/‖A⁻¹‖₂ ≥ 1/‖A⁻¹‖_F
/// (it only sizes the sphere, so a bound is enough).
fn smallest_singular_value(a: DMat3) -> f64 {
    let inv = a.inverse();
    let frob = inv
        .to_cols_array()
        .iter()
        .map(|x| x * x)
        .sum::<f64>()
        .sqrt();
    1.0 / frob
}

/// The catalogue's X1: four nested instance levels, each a transform the
/// shell composes in f64 and the `transform` plugin applies in f32, around a
/// sphere. Paths start at the instance's centre and bounce inside it, like
/// S5's furnace: every ray from inside must hit (escapes), every ray spawned
/// outwards must hit nothing (the ellipsoid is convex: self-hits), and every
/// world hit point must lie within its propagated bound.
fn nested_transforms_keep_rays_inside_and_hits_in_bounds(b: &mut Bench) -> Result<Vec<Line>> {
    let chains = b.n(16, 256);
    let paths = b.n(300, 2000);
    const BOUNCES: u32 = 8;
    let mut rng = RngState::seeded(0x71);
    let mut c = Checks::default();
    let (mut escapes, mut self_hits, mut spawned) = (0u64, 0u64, 0u64);
    let mut worst_reach = 0.0f64;
    for _ in 0..chains {
        let (levels, r, m) = chain(&mut rng);
        let mut toml = format!(
            "{}[objects.ball]\nclass = \"sphere\"\nradius = {}\n",
            header("l0"),
            num(r as f64)
        );
        for (k, l) in levels.iter().enumerate() {
            let child = if k == 3 {
                "ball".to_string()
            } else {
                format!("l{}", k + 1)
            };
            toml += &format!(
                "[objects.l{k}]\nclass = \"list\"\nchildren = [{{ object = \"{child}\", transform = {} }}]\n",
                l.toml()
            );
        }
        let world = b.scene(&toml)?;
        let mut probe = Probe::new(&world);
        let e = Ellipsoid::new(m, r);
        let centre = m.translation;
        worst_reach = worst_reach.max(centre.length());
        for _ in 0..paths {
            let mut r = ray(centre, unit_vector(&mut rng));
            for _ in 0..BOUNCES {
                let Some(hit) = probe.nearest(&r)? else {
                    escapes += 1;
                    break;
                };
                let g = probe.geom(&r, &hit)?;
                c.hit(&e, &r, &hit, &g);
                let n = g.ng.v().as_dvec3();
                spawned += 1;
                let out = spawn_ray(&g, hemisphere(&mut rng, n).as_vec3(), &r);
                if probe.nearest(&out)?.is_some() {
                    self_hits += 1;
                }
                r = spawn_ray(&g, hemisphere(&mut rng, -n).as_vec3(), &r);
            }
        }
    }
    let setup = format!("{chains} chains x {paths} paths x {BOUNCES}");
    Ok(vec![
        Line::count(&setup, "escapes from inside", escapes),
        Line::count(
            format!("{spawned} outward spawned rays"),
            "self-hits",
            self_hits,
        ),
        Line::count(&setup, "non-finite t or geometry", c.non_finite),
        Line::count(
            format!("{} hits, |c| up to {:.0e}", c.hits, worst_reach),
            "off surface > offset",
            c.off_surface,
        ),
    ])
}

/// The catalogue's X2. Singular, non-finite and badly conditioned
/// transforms must be refused when the scene is built; a valid near-flat
/// scale (1, 1, 1e-6), rotated, must give finite unit normals and the f64
/// reference's hits.
fn bad_transforms_are_refused_and_flat_ones_exact(b: &mut Bench) -> Result<Vec<Line>> {
    let mut lines = vec![invalid_transforms_refused(b)?];
    lines.extend(near_flat_instance(b)?);
    Ok(lines)
}

/// Singular, non-finite and badly conditioned transforms: one line, the
/// count of those the shell accepted (named in its setup when any is).
fn invalid_transforms_refused(b: &mut Bench) -> Result<Line> {
    // A shear [[1, s, 0], [0, 1, 0], [0, 0, 1]] has Frobenius condition
    // number 3 + s²: s = √(1e8 − 3) makes it 1e8.
    let s = (1e8f64 - 3.0).sqrt();
    let invalid = [
        (
            "scale (1,1,1e-20)",
            "[{ scale = [1.0, 1.0, 1e-20] }]".to_string(),
        ),
        ("scale (1,1,0)", "[{ scale = [1.0, 1.0, 0.0] }]".to_string()),
        (
            "shear, condition 1e8",
            format!(
                "[{{ matrix = [1.0, {}, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0] }}]",
                num(s)
            ),
        ),
        (
            "matrix with a NaN",
            "[{ matrix = [1.0, 0.0, 0.0, 0.0, 0.0, nan, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0] }]"
                .to_string(),
        ),
    ];
    let mut accepted = Vec::new();
    for (what, steps) in &invalid {
        let toml = format!(
            "{}[objects.ball]\nclass = \"sphere\"\n\
             [objects.world]\nclass = \"list\"\nchildren = [{{ object = \"ball\", transform = {steps} }}]\n",
            header("world")
        );
        if b.build_error(&toml).is_none() {
            accepted.push(*what);
        }
    }
    let mut line = Line::count(
        format!("{} invalid transforms", invalid.len()),
        "accepted",
        accepted.len() as u64,
    );
    if !accepted.is_empty() {
        line.setup = format!("accepted: {}", accepted.join(", "));
    }
    Ok(line)
}

/// The valid near-flat scale (1, 1, 1e-6), rotated: finite unit normals,
/// the f64 reference's hits and t, no outward self-hits.
fn near_flat_instance(b: &mut Bench) -> Result<Vec<Line>> {
    // A unit sphere squashed to a 2e-6 thick disk, turned by a random
    // rotation, seen from random points 5 away.
    let mut rng = RngState::seeded(0x72);
    let level = Level {
        scale: DVec3::new(1.0, 1.0, 1e-6),
        axis: unit_vector(&mut rng),
        degrees: 360.0 * rng.next_f64(),
        translate: DVec3::new(0.5, -0.25, 2.0),
    };
    let world = b.scene(&format!(
        "{}[objects.ball]\nclass = \"sphere\"\n\
         [objects.world]\nclass = \"list\"\nchildren = [{{ object = \"ball\", transform = {} }}]\n",
        header("world"),
        level.toml()
    ))?;
    let e = Ellipsoid::new(level.matrix(), 1.0);
    let mut probe = Probe::new(&world);
    let n = b.n(50_000, 200_000);
    let (mut mismatches, mut bad_normals, mut self_hits) = (0u64, 0u64, 0u64);
    let mut c = Checks::default();
    for _ in 0..n {
        let o = level.translate + unit_vector(&mut rng) * 5.0;
        let aim = level.translate + unit_vector(&mut rng) * (1.2 * rng.next_f64().cbrt());
        let r = ray(o, (aim - o).normalize());
        let got = probe.nearest(&r)?;
        if got.is_some() != e.hit(&r).is_some() {
            mismatches += 1;
        }
        let Some(hit) = got else { continue };
        let g = probe.geom(&r, &hit)?;
        c.hit(&e, &r, &hit, &g);
        // Leaving the convex ellipsoid outwards, a ray never meets it again.
        let out = if g.ng.v().dot(r.dir.v()) < 0.0 {
            g.ng.v()
        } else {
            -g.ng.v()
        };
        let s = spawn_ray(&g, hemisphere(&mut rng, out.as_dvec3()).as_vec3(), &r);
        if probe.nearest(&s)?.is_some() {
            self_hits += 1;
        }
        for nrm in [g.ng.v(), g.ns.v()] {
            if !(nrm.is_finite() && (nrm.length() - 1.0).abs() <= 1e-5) {
                bad_normals += 1;
            }
        }
    }
    let setup = format!("scale (1,1,1e-6) rotated, {n} rays");
    Ok(vec![
        Line::count(&setup, "non-finite or non-unit normals", bad_normals),
        Line::count(&setup, "non-finite t or geometry", c.non_finite),
        Line::new(
            &setup,
            "hit/miss mismatch rate",
            mismatches as f64 / n as f64,
            // In object space the rays come from up to 5e6 away (the
            // squashed axis is stretched 1e6-fold): the catalogue's Q1
            // band at its largest D/r, 1e6.
            Target::AtMost(5e-3),
        ),
        Line::new(&setup, "max rel t error", c.worst_t, Target::AtMost(1e-5)),
        // Not X1's distance-from-surface check: at the rim of a 1e-6-thin
        // ellipsoid the curvature radius is 1e-12, far below a point's
        // rounding, and no f64 projection measures the distance there (one
        // hit in 50,000 reads 35 times its offset). Whether the offset
        // clears the surface is what the self-hit count measures directly.
        Line::count(&setup, "outward self-hits", self_hits),
    ])
}

/// The catalogue's X3: one small scene (a floor, a clay ball, a mirror
/// ball, a point and a directional light, Whitted), rendered with the
/// camera, the lights and every instance moved by (t, t, t). Every number
/// in it is a multiple of 1/32, so the moved scene is exactly representable
/// in f32 up to t = 5e5 (spacing 1/32): any difference from the unmoved
/// image comes from the arithmetic, not from the scene. The metric is the
/// RMSE over all pixels and channels divided by the unmoved image's RMS.
/// Camera-relative rendering (`[render] origin`, default the eye) is what
/// passes it: with `origin = "world"` these renders differ by 1.0e-2 (1e4)
/// and 5.2e-2 (5e5).
fn scenes_far_from_the_origin_render_the_same(b: &mut Bench) -> Result<Vec<Line>> {
    let (w, h) = (b.n(64, 320), b.n(48, 240));
    b.write_obj("floor.obj", &floor())?;
    let mut reference: Option<Vec<[f64; 3]>> = None;
    let mut lines = Vec::new();
    for t in [0.0, 1e4, 5e5] {
        let at = |x: f64, y: f64, z: f64| vec3([x + t, y + t, z + t]);
        let moved = |x: f64, y: f64, z: f64| format!("{{ translate = {} }}", at(x, y, z));
        let world = b.scene(&format!(
            "[render]\nwidth = {w}\nheight = {h}\nroot = \"world\"\nbackground = [0.3, 0.4, 0.6]\n\
             integrator = {{ class = \"whitted\", max_depth = 4 }}\n\
             [cameras.c]\nclass = \"pinhole\"\neye = {}\nlook_at = {}\nfov_y = 40.0\n\
             [lights.key]\nclass = \"point\"\nposition = {}\nintensity = [60.0, 60.0, 60.0]\n\
             [lights.sun]\nclass = \"directional\"\ndirection = [-0.375, -1.0, -0.625]\n\
             [shaders.floor]\nclass = \"lambert\"\nalbedo = [0.7, 0.7, 0.7]\n\
             [shaders.clay]\nclass = \"phong\"\ndiffuse = [0.8, 0.55, 0.4]\nspecular = [0.2, 0.2, 0.2]\n\
             [shaders.mirror]\nclass = \"phong\"\ndiffuse = [0.05, 0.05, 0.05]\nmirror = [0.8, 0.8, 0.8]\n\
             [objects.floor]\nclass = \"mesh\"\nfile = \"floor.obj\"\n\
             [objects.ball]\nclass = \"sphere\"\n\
             [objects.world]\nclass = \"list\"\nchildren = [\n\
             {{ object = \"floor\", shader = \"floor\", transform = [{{ scale = 8.0 }}, {}] }},\n\
             {{ object = \"ball\", shader = \"clay\", transform = [{}] }},\n\
             {{ object = \"ball\", shader = \"mirror\", transform = [{{ scale = 0.625 }}, {}] }},\n]\n",
            at(0.0, 2.0, 8.0),
            at(0.0, 0.5, 0.0),
            at(4.0, 6.0, 4.0),
            moved(0.0, 0.0, 0.0),
            moved(-1.25, 1.0, 0.0),
            moved(1.25, 0.625, 0.75),
        ))?;
        let film = b.render(&world)?;
        let Some(r) = &reference else {
            reference = Some(film.pixels);
            continue;
        };
        let (mut se, mut ss) = (0.0f64, 0.0f64);
        for (p, q) in film.pixels.iter().zip(r) {
            for c in 0..3 {
                se += (p[c] - q[c]).powi(2);
                ss += q[c] * q[c];
            }
        }
        lines.push(Line::new(
            format!("moved by {} on each axis, {w}x{h}", mag(t)),
            "RMSE / RMS of unmoved",
            (se / ss).sqrt(),
            Target::AtMost(1e-4),
        ));
    }
    Ok(lines)
}

/// A floor square, ±1 in x and z at y = 0, facing up.
fn floor() -> Mesh {
    Mesh {
        verts: vec![
            [-1.0, 0.0, -1.0],
            [1.0, 0.0, -1.0],
            [1.0, 0.0, 1.0],
            [-1.0, 0.0, 1.0],
        ],
        tris: vec![[0, 2, 1], [0, 3, 2]],
    }
}
