//! I1–I3, the integrator-level closed forms of docs/numerics.md: whole
//! renders by the `path` integrator through the render loop, compared with
//! an exact expectation. Each line is the image's deviation from it in
//! standard errors of the mean: `|mean − exact| / (σ / √pixels)`, σ the
//! spread of the pixels' residuals (each pixel an independent estimate).
//! The renders are seeded, so a line is reproducible, not flaky; a bias (an
//! energy, density or self-intersection bug, a ray leaking out of an
//! enclosure) moves the mean by many standard errors.

use super::bench::*;
use super::Case;
use crate::render::render_loop::Film;
use anyhow::Result;
use rtk_kernel::abi::{CameraSample, TraceCtx};
use rtk_kernel::glam::DVec3;

/// docs/numerics.md I1.
pub const I1: Case = Case {
    id: "I1",
    title: "white furnace: a convex Lambert object under a constant sky",
    run: convex_object_reflects_albedo_times_sky,
};

/// docs/numerics.md I2.
pub const I2: Case = Case {
    id: "I2",
    title: "enclosure furnace: inside an emitting Lambert box, L = Le/(1-rho)",
    run: enclosure_radiance_is_emission_over_one_minus_albedo,
};

/// docs/numerics.md I3.
pub const I3: Case = Case {
    id: "I3",
    title: "black ball on a Lambert plane under a constant sky: the form factor",
    run: plane_under_a_black_ball_matches_the_form_factor,
};

/// Most standard errors a mean may lie from its expectation.
const Z_MAX: f64 = 4.0;

/// The image's mean deviation from `exact` (per pixel, `None`: not
/// compared) in standard errors; green channel (all three are alike here).
fn z_of(film: &Film, exact: impl Fn(usize) -> Option<f64>) -> (f64, usize) {
    let res: Vec<f64> = film
        .pixels
        .iter()
        .enumerate()
        .filter_map(|(i, p)| exact(i).map(|e| p[1] - e))
        .collect();
    let n = res.len().max(2) as f64;
    let mean = res.iter().sum::<f64>() / n;
    let var = res.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / (n - 1.0);
    let se = (var / n).sqrt().max(1e-300);
    (mean.abs() / se, res.len())
}

fn z_line(setup: String, z: f64) -> Line {
    Line::new(setup, "|mean-exact|/stderr", z, Target::AtMost(Z_MAX))
}

/// The render settings of every case: `path`, Russian roulette from the
/// first bounce (so that the furnace's long paths end), world origin.
fn render_header(size: usize, spp: usize, root: &str) -> String {
    format!(
        "[render]\nwidth = {size}\nheight = {size}\nspp = {spp}\nroot = \"{root}\"\norigin = \"world\"\n\
         integrator = {{ class = \"path\", rr_depth = 1 }}\n"
    )
}

/// I1: a Lambert ball of albedo ρ under a constant sky L: one bounce
/// reaches the sky (a convex object cannot see itself), so every pixel on
/// it has expectation ρL. With the camera close, every pixel sees the ball;
/// with ρ = 1 the ball is invisible and every pixel is L. At the origin and
/// far from it.
fn convex_object_reflects_albedo_times_sky(b: &mut Bench) -> Result<Vec<Line>> {
    let (size, spp) = (b.n(48, 128), b.n(32, 128));
    let mut lines = Vec::new();
    for &(dist, albedo) in &[(0.0, 0.5), (0.0, 1.0), (1e4, 0.5)] {
        let c = DVec3::splat(dist);
        let world = b.scene(&format!(
            "{}[cameras.c]\nclass = \"pinhole\"\neye = {}\nlook_at = {}\nfov_y = 20.0\n\
             [lights.sky]\nclass = \"constant\"\nradiance = [0.8, 0.8, 0.8]\n\
             [shaders.clay]\nclass = \"lambert\"\nalbedo = [{albedo:?}, {albedo:?}, {albedo:?}]\n\
             [objects.ball]\nclass = \"sphere\"\ncenter = {}\nradius = 1.0\n\
             [objects.world]\nclass = \"list\"\nchildren = [{{ object = \"ball\", shader = \"clay\" }}]\n",
            render_header(size, spp, "world"),
            vec3((c + DVec3::new(0.0, 0.0, 2.5)).to_array()),
            vec3(c.to_array()),
            vec3(c.to_array()),
        ))?;
        let film = b.render(&world)?;
        let (z, _) = z_of(&film, |_| Some(albedo * 0.8));
        lines.push(z_line(
            format!("ball rho {albedo} |c| {}, {size}^2 x {spp}", mag(dist)),
            z,
        ));
    }
    Ok(lines)
}

/// I2: the camera inside a closed box whose inner walls (Lambert, ρ = 0.5)
/// emit Le = 0.5: L = Le + ρL everywhere, so every pixel's expectation is
/// Le/(1 − ρ) = 1 whatever the path lengths; a path that leaks out sees the
/// black background and pulls the mean down. At the origin and far from it.
fn enclosure_radiance_is_emission_over_one_minus_albedo(b: &mut Bench) -> Result<Vec<Line>> {
    let (size, spp) = (b.n(48, 128), b.n(32, 128));
    let mut lines = Vec::new();
    for &dist in &[0.0, 1e3, 1e5] {
        let c = DVec3::splat(dist);
        let mut walls = box_mesh(c, DVec3::new(1.0, 1.5, 2.0));
        // Wound inwards: a Lambert surface emits on its front side.
        for t in &mut walls.tris {
            t.swap(1, 2);
        }
        b.write_obj("walls.obj", &walls)?;
        let world = b.scene(&format!(
            "{}[cameras.c]\nclass = \"pinhole\"\neye = {}\nlook_at = {}\nfov_y = 100.0\n\
             [shaders.wall]\nclass = \"lambert\"\nalbedo = [0.5, 0.5, 0.5]\nemission = [0.5, 0.5, 0.5]\n\
             [objects.walls]\nclass = \"mesh\"\nfile = \"walls.obj\"\n\
             [objects.world]\nclass = \"list\"\nchildren = [{{ object = \"walls\", shader = \"wall\" }}]\n",
            render_header(size, spp, "world"),
            vec3((c + DVec3::new(0.1, 0.2, 0.3)).to_array()),
            vec3((c + DVec3::new(0.9, -0.7, 1.9)).to_array()),
        ))?;
        let film = b.render(&world)?;
        let (z, _) = z_of(&film, |_| Some(1.0));
        lines.push(z_line(
            format!("box |c| {}, {size}^2 x {spp}", mag(dist)),
            z,
        ));
    }
    Ok(lines)
}

/// What a film position looks at in I3's scene, in f64 from the camera's
/// own ray: the ball (radius `r` at `c`), the plane y = 0 within `half` of
/// the origin, or the sky.
#[derive(PartialEq)]
enum Seen {
    Ball,
    Plane(DVec3),
    Sky,
}

fn seen(o: DVec3, d: DVec3, c: DVec3, r: f64, half: f64) -> Seen {
    let oc = o - c;
    let (bq, cq) = (oc.dot(d), oc.length_squared() - r * r);
    if bq * bq - cq >= 0.0 && -bq - (bq * bq - cq).sqrt() > 0.0 {
        return Seen::Ball;
    }
    if d.y < 0.0 {
        let p = o + d * (-o.y / d.y);
        if p.x.abs() < half && p.z.abs() < half {
            return Seen::Plane(p);
        }
    }
    Seen::Sky
}

/// I3: a Lambert plane (ρ = 0.5) under a constant sky L = 1, and a black
/// ball of radius r resting on it (centre height h = r): a plane point at
/// distance d from the centre receives L(1 − r²h/d³) (the sky less the
/// ball's form factor), so its radiance is ρL(1 − r²h/d³), 0 at the
/// contact point; the ball is 0 and the sky L. Pixels whose corners see
/// different things (silhouettes, the contact) are left out.
fn plane_under_a_black_ball_matches_the_form_factor(b: &mut Bench) -> Result<Vec<Line>> {
    let (size, spp) = (b.n(64, 128), b.n(64, 128));
    let (c, r, half) = (DVec3::new(0.0, 1.0, 0.0), 1.0, 50.0);
    b.write_obj(
        "plane.obj",
        &Mesh {
            verts: vec![
                [-half as f32, 0.0, -half as f32],
                [half as f32, 0.0, -half as f32],
                [half as f32, 0.0, half as f32],
                [-half as f32, 0.0, half as f32],
            ],
            tris: vec![[0, 2, 1], [0, 3, 2]],
        },
    )?;
    let world = b.scene(&format!(
        "{}[cameras.c]\nclass = \"pinhole\"\neye = [0.0, 4.0, 5.0]\nlook_at = [0.0, 0.5, 0.0]\nfov_y = 60.0\n\
         [lights.sky]\nclass = \"constant\"\n\
         [shaders.ground]\nclass = \"lambert\"\nalbedo = [0.5, 0.5, 0.5]\n\
         [shaders.black]\nclass = \"lambert\"\nalbedo = [0.0, 0.0, 0.0]\n\
         [objects.plane]\nclass = \"mesh\"\nfile = \"plane.obj\"\n\
         [objects.ball]\nclass = \"sphere\"\ncenter = {}\nradius = {r:?}\n\
         [objects.world]\nclass = \"list\"\nchildren = [{{ object = \"plane\", shader = \"ground\" }}, \
         {{ object = \"ball\", shader = \"black\" }}]\n",
        render_header(size, spp, "world"),
        vec3(c.to_array()),
    ))?;
    let film = b.render(&world)?;
    let (exact, plane_pixels) = expected_pixels(&world, size, (c, r, half));
    let (z, compared) = z_of(&film, |i| exact[i]);
    Ok(vec![
        z_line(
            format!("plane, ball r 1 h 1, {compared} px ({plane_pixels} plane) x {spp}"),
            z,
        ),
        Line::new(
            format!("plane pixels of {size}^2"),
            "share of the image",
            plane_pixels as f64 / (size * size) as f64,
            Target::AtLeast(0.3),
        ),
    ])
}

/// I3's expectation per pixel of a `size`² image of `world` (`None` where
/// the pixel's corners see different things), and how many pixels see the
/// plane; the ball is `(centre, radius)`, the plane's half-width `half`.
fn expected_pixels(
    world: &rtk_shell::World,
    size: usize,
    (c, r, half): (DVec3, f64, f64),
) -> (Vec<Option<f64>>, u64) {
    let mut ctx = TraceCtx::new(0, 1, 0);
    let mut look = |x: f64, y: f64| -> Seen {
        let s = CameraSample {
            film: [(x / size as f64) as f32, (y / size as f64) as f32],
            lens: [0.5, 0.5],
            time: 0.5,
        };
        match world.camera.generate_ray(&mut ctx, &s) {
            Some(cr) => seen(
                cr.ray.origin.v().as_dvec3(),
                cr.ray.dir.v().as_dvec3().normalize(),
                c,
                r,
                half,
            ),
            None => Seen::Sky,
        }
    };
    let mut exact = Vec::with_capacity(size * size);
    let mut plane_pixels = 0u64;
    for py in 0..size {
        for px in 0..size {
            let (x, y) = (px as f64, py as f64);
            let corners = [(x, y), (x + 1.0, y), (x, y + 1.0), (x + 1.0, y + 1.0)];
            let kinds: Vec<Seen> = corners.iter().map(|&(u, v)| look(u, v)).collect();
            let same = kinds
                .iter()
                .all(|k| std::mem::discriminant(k) == std::mem::discriminant(&kinds[0]));
            exact.push(match (same, look(x + 0.5, y + 0.5)) {
                (false, _) => None,
                (true, Seen::Ball) => Some(0.0),
                (true, Seen::Sky) => Some(1.0),
                (true, Seen::Plane(p)) => {
                    plane_pixels += 1;
                    let d = (c - p).length();
                    Some(0.5 * (1.0 - r * r * c.y / d.powi(3)))
                }
            });
        }
    }
    (exact, plane_pixels)
}
