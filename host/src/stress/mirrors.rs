//! S5, the house of mirrors: deep specular chains must never leave a closed
//! mirror, at any distance from the origin.

use super::bench::*;
use super::Case;
use anyhow::Result;
use rtk_kernel::geom::spawn_ray;
use rtk_kernel::glam::DVec3;
use rtk_kernel::sdk::shading::reflect_at;
use rtk_kernel::RngState;

/// docs/numerics.md S5.
pub const S5: Case = Case {
    id: "S5",
    title: "house of mirrors: deep specular chains in closed mirrors",
    run: specular_chains_never_leave_a_closed_mirror,
};

/// S5's three setups: the mirror furnace, two parallel mirrors, and a
/// rendered house of mirrors.
fn specular_chains_never_leave_a_closed_mirror(b: &mut Bench) -> Result<Vec<Line>> {
    let mut lines = furnace(b)?;
    lines.extend(parallel_mirrors(b)?);
    lines.extend(rendered(b)?);
    Ok(lines)
}

/// Setup A: inside a mirror sphere (the `sphere` plugin) of reflectance
/// R = 0.9 that emits Le = 0.1 at every hit, a path of N + 1 hits carries
/// exactly Le(1 − R^(N+1))/(1 − R). Paths start at random interior points in
/// random directions and follow the mirror the way a mirror lobe does
/// (`reflect_at`, then `spawn_ray`). Emission joins the integrators with the
/// path tracer (ROADMAP): until then the sum is taken here, and what it
/// checks is that every path makes all its bounces inside.
fn furnace(b: &mut Bench) -> Result<Vec<Line>> {
    const BOUNCES: u32 = 64;
    const R: f64 = 0.9;
    const LE: f64 = 0.1;
    let paths = b.n(300, 20_000);
    let exact = LE * (1.0 - R.powi(BOUNCES as i32 + 1)) / (1.0 - R);
    let mut lines = Vec::new();
    let mut rng = RngState::seeded(0x55);
    for &(dist, r) in &[
        (0.0, 1.0),
        (1e3, 1.0),
        (1e4, 10.0),
        (1e5, 1.0),
        (0.0, 1e-3),
        (1e3, 1e-3),
    ] {
        let c = unit_vector(&mut rng) * dist;
        let world = b.scene(&format!(
            "{}[objects.ball]\nclass = \"sphere\"\ncenter = {}\nradius = {}\n",
            header("ball"),
            vec3(c.to_array()),
            num(r)
        ))?;
        let mut probe = Probe::new(&world);
        let (mut escapes, mut worst) = (0u64, 0.0f64);
        for _ in 0..paths {
            let o = c + unit_vector(&mut rng) * (0.5 * r * rng.next_f64());
            let mut ray = ray(o, unit_vector(&mut rng));
            let (mut l, mut throughput) = (0.0f64, 1.0f64);
            let mut escaped = false;
            for _ in 0..=BOUNCES {
                let Some(hit) = probe.nearest(&ray)? else {
                    escaped = true;
                    break;
                };
                l += throughput * LE;
                throughput *= R;
                let g = probe.geom(&ray, &hit)?;
                let wo = -ray.dir.v().normalize();
                let ns = g.ns.v();
                let n = if ns.dot(wo) < 0.0 { -ns } else { ns };
                ray = spawn_ray(&g, reflect_at(&g, wo, n), &ray);
            }
            if escaped {
                escapes += 1;
            } else {
                worst = worst.max((l - exact).abs() / exact);
            }
        }
        let setup = format!("A sphere |c| {} r {}", mag(dist), mag(r));
        lines.push(Line::count(&setup, "escapes", escapes));
        lines.push(Line::new(
            setup,
            "max |L-L_N|/L_N",
            worst,
            Target::AtMost(1e-12),
        ));
    }
    Ok(lines)
}

/// Setup B: two parallel mirror quads, 1000 x 1000, at x = 0 and x = 1;
/// from (0.5, 0, 0) along (1, 1e-3, 0), hit k lies at x ∈ {0, 1} and at
/// y_k = (k − ½)·d_y/d_x, each within the error bounds propagated along the
/// path (the hit points' own bounds plus the offsets' drift along y).
fn parallel_mirrors(b: &mut Bench) -> Result<Vec<Line>> {
    let bounces = b.n(200, 2000);
    let quad = |x: f32| {
        [
            [x, -500.0, -500.0],
            [x, 500.0, -500.0],
            [x, 500.0, 500.0],
            [x, -500.0, 500.0],
        ]
    };
    let mut verts = quad(0.0).to_vec();
    verts.extend(quad(1.0));
    let mesh = Mesh {
        verts,
        tris: vec![[0, 1, 2], [0, 2, 3], [4, 6, 5], [4, 7, 6]],
    };
    b.write_obj("mirrors.obj", &mesh)?;
    let world = b.scene(&format!(
        "{}[objects.m]\nclass = \"mesh\"\nfile = \"mirrors.obj\"\n",
        header("m")
    ))?;
    let mut probe = Probe::new(&world);
    let mut ray = ray(
        DVec3::new(0.5, 0.0, 0.0),
        DVec3::new(1.0, 1e-3, 0.0).normalize(),
    );
    let slope = ray.dir.y as f64 / ray.dir.x as f64;
    let (mut violations, mut escapes, mut bound) = (0u64, 0u64, 0.0f64);
    // The plane the current ray left: its origin's distance from it (the
    // offset) turns into drift along y.
    let mut left: Option<f64> = None;
    for k in 1..=bounces {
        let Some(hit) = probe.nearest(&ray)? else {
            escapes += 1;
            break;
        };
        let g = probe.geom(&ray, &hit)?;
        let (p, e) = (g.p.v().as_dvec3(), g.p_err.v().as_dvec3());
        if let Some(w) = left {
            bound += (ray.origin.x as f64 - w).abs() * slope.abs();
        }
        bound += e.y;
        let wall = if k % 2 == 1 { 1.0 } else { 0.0 };
        let y = (k as f64 - 0.5) * slope;
        if (p.x - wall).abs() > e.x || (p.y - y).abs() > bound {
            violations += 1;
        }
        left = Some(wall);
        let wo = -ray.dir.v().normalize();
        let ns = g.ns.v();
        let n = if ns.dot(wo) < 0.0 { -ns } else { ns };
        ray = spawn_ray(&g, reflect_at(&g, wo, n), &ray);
    }
    let setup = format!("B parallel quads, {bounces} hits");
    Ok(vec![
        Line::count(&setup, "escapes", escapes),
        Line::count(setup, "bound violations", violations),
    ])
}

/// Setup C through `rtk render`'s own loop: a camera inside a closed mirror
/// box (12 triangles, axis-aligned and rotated) and inside a closed mirror
/// sphere mesh (face normals, and smooth vertex normals, whose mirror
/// directions can dip below the facets), Whitted at depth 1000, a white
/// background and black mirrors: every pixel that is not black is a path
/// that escaped. The scenes are rendered about the world's origin
/// (`origin = "world"`): camera-relative rendering would bring every
/// enclosure back to the origin and hide what this measures.
fn rendered(b: &mut Bench) -> Result<Vec<Line>> {
    let size = b.n(48, 256);
    let mut lines = Vec::new();
    let mut rng = RngState::seeded(0x5c);
    for &dist in &[0.0, 1e3, 1e5] {
        let c = DVec3::splat(dist);
        let turn = rotation(&mut rng);
        let mut tilted = box_mesh(DVec3::ZERO, DVec3::ONE);
        for v in &mut tilted.verts {
            *v = (c + turn * DVec3::from(v.map(f64::from)))
                .as_vec3()
                .to_array();
        }
        for (shape, mesh, normals) in [
            ("box", box_mesh(c, DVec3::ONE), "face"),
            ("rotated box", tilted, "face"),
            ("sphere mesh", uv_sphere(c, 24, 48, |_| 1.0), "face"),
            (
                "smooth sphere mesh",
                uv_sphere(c, 24, 48, |_| 1.0),
                "vertex",
            ),
        ] {
            b.write_obj("enclosure.obj", &mesh)?;
            let world = b.scene(&format!(
                "[render]\nwidth = {size}\nheight = {size}\nroot = \"world\"\norigin = \"world\"\n\
                 background = [1.0, 1.0, 1.0]\n\
                 integrator = {{ class = \"whitted\", max_depth = 1000 }}\n\
                 [cameras.c]\nclass = \"pinhole\"\neye = {}\nlook_at = {}\nfov_y = 90.0\n\
                 [shaders.mirror]\nclass = \"phong\"\ndiffuse = [0.0, 0.0, 0.0]\nmirror = [1.0, 1.0, 1.0]\n\
                 [objects.m]\nclass = \"mesh\"\nfile = \"enclosure.obj\"\nnormals = \"{normals}\"\n\
                 [objects.world]\nclass = \"list\"\nchildren = [{{ object = \"m\", shader = \"mirror\" }}]\n",
                vec3((c + DVec3::new(0.1, 0.2, 0.3)).to_array()),
                vec3((c + DVec3::new(0.5, -0.2, -0.7)).to_array()),
            ))?;
            let film = b.render(&world)?;
            let escaped = film
                .pixels
                .iter()
                .filter(|p| p.iter().any(|&v| v != 0.0))
                .count();
            lines.push(Line::count(
                format!("C {shape} |c| {}, {size}^2 x 1000", mag(dist)),
                "escaped pixels",
                escaped as u64,
            ));
        }
    }
    Ok(lines)
}
